// The compensator's own pipeline stages as compared quantities: the core compensator (default
// mode) runs over a recording, and its constant-bias estimate, dominant frequency, velocity and
// position (and wave motion) are reduced per level axis and time segment.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/gap/truth.h"

namespace periodic_bias_compensation::gap
{
namespace
{
/// Stage quantities, in feature order per axis: name, floor, relative floor.
struct StageQuantity
{
  const char* name;
  double floor;
  double rel_floor;
};
constexpr StageQuantity kStages[] = {
  { "comp_bias", 1e-4, 0.0 },        // constant-bias estimate at the segment's end [m/s^2]
  { "comp_frequency", 5e-3, 0.02 },  // median dominant frequency while locked [Hz] (0: never)
  { "comp_velocity", 1e-3, 0.05 },   // rms of the filtered velocity [m/s]
  { "comp_position", 1e-2, 0.05 },   // rms of the filtered position (error growth) [m]
  { "comp_wave", 1e-3, 0.05 },       // rms of the wave position [m]
};
constexpr int kStageCount = sizeof(kStages) / sizeof(kStages[0]);
const char* const kLevelAxes[3] = { "x", "y", "z" };
}  // namespace

FeatureLayout stageLayout(double duration, int segments)
{
  FeatureLayout L;
  L.segments = segments;
  for (int a = 0; a < 3; ++a)
  {
    for (const StageQuantity& q : kStages)
    {
      for (int s = 0; s < segments; ++s)
      {
        FeatureInfo f =
            segmentInfo(std::string("level ") + kLevelAxes[a], q.name, "compensator", duration, s, segments);
        f.floor = q.floor;
        f.rel_floor = q.rel_floor;
        L.info.push_back(f);
      }
    }
  }
  return L;
}

std::vector<double> stageFeatures(const Recording& r, int segments)
{
  Compensator comp;  // default mode and configuration, as a crew would start
  const std::size_t n = r.size();
  // per segment, axis: sums for the rms values, frequencies while locked, last bias
  std::vector<std::array<double, 3>> bias(segments), v2(segments), p2(segments), w2(segments);
  std::vector<std::array<std::vector<double>, 3>> freq(segments);
  std::vector<double> count(segments, 0.0);
  CompensatorOutput out;
  const double t0 = n > 0 ? r.stamp.front() : 0.0;
  const double span = n > 1 ? std::max(1e-9, r.stamp.back() - t0) : 1.0;
  for (auto* v : { &bias, &v2, &p2, &w2 })
  {
    for (auto& a : *v)
    {
      a = { 0.0, 0.0, 0.0 };
    }
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    ImuSample s;
    s.t = r.stamp[i];
    s.specific_force = r.data.row(i).head<3>().transpose();
    s.angular_rate = r.data.row(i).tail<3>().transpose();
    if (r.has_orientation && i < r.orientation.size())
    {
      s.has_orientation = true;
      s.orientation = r.orientation[i];
    }
    if (comp.addSample(s, &out) != SampleStatus::kAccepted || !out.calibrated)
    {
      continue;
    }
    const int seg = std::min(segments - 1, static_cast<int>(segments * (r.stamp[i] - t0) / span));
    count[seg] += 1.0;
    for (int a = 0; a < 3; ++a)
    {
      bias[seg][a] = out.axes[a].constant_bias;
      v2[seg][a] += out.velocity_filtered[a] * out.velocity_filtered[a];
      p2[seg][a] += out.position_filtered[a] * out.position_filtered[a];
      w2[seg][a] += out.position_wave[a] * out.position_wave[a];
      if (out.axes[a].locked)
      {
        freq[seg][a].push_back(out.axes[a].frequency);
      }
    }
  }
  std::vector<double> f;
  for (int a = 0; a < 3; ++a)
  {
    for (int q = 0; q < kStageCount; ++q)
    {
      for (int s = 0; s < segments; ++s)
      {
        const double c = std::max(1.0, count[s]);
        std::vector<double>& fr = freq[s][a];
        double v = 0.0;
        switch (q)
        {
          case 0:
            v = bias[s][a];
            break;
          case 1:
            if (!fr.empty())
            {
              v = upperMedian(fr.begin(), fr.end());
            }
            break;
          case 2:
            v = std::sqrt(v2[s][a] / c);
            break;
          case 3:
            v = std::sqrt(p2[s][a] / c);
            break;
          default:
            v = std::sqrt(w2[s][a] / c);
            break;
        }
        f.push_back(std::isfinite(v) ? v : 0.0);
      }
    }
  }
  return f;
}
}  // namespace periodic_bias_compensation::gap
