// Sample-by-sample comparison with a truth: the ideal IMU a truth track drives (specific force and
// angular rate in the body frame), and the residual real minus ideal per channel and segment.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "periodic_bias_compensation/gap/signal.h"
#include "periodic_bias_compensation/gap/truth.h"
#include "periodic_bias_compensation/sim/simulator.h"

namespace periodic_bias_compensation::gap
{
namespace
{
/// Central differences of a vector series on its (non-uniform) time base.
std::vector<Eigen::Vector3d> differentiate(const std::vector<Eigen::Vector3d>& x, const std::vector<double>& t)
{
  const std::size_t n = x.size();
  std::vector<Eigen::Vector3d> d(n, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n && n >= 2; ++i)
  {
    const std::size_t a = i > 0 ? i - 1 : 0, b = std::min(n - 1, i + 1);
    const double dt = t[b] - t[a];
    d[i] = dt > 0 ? Eigen::Vector3d((x[b] - x[a]) / dt) : Eigen::Vector3d::Zero();
  }
  return d;
}

/// Index of the last truth sample at or before t (0 if none), for a forward sweep.
std::size_t advance(const std::vector<double>& s, double t, std::size_t j)
{
  while (j + 1 < s.size() && s[j + 1] <= t)
  {
    ++j;
  }
  return j;
}
}  // namespace

Eigen::MatrixXd movingAverage(const Eigen::MatrixXd& x, double rate, double smooth)
{
  const Eigen::Index n = x.rows();
  const Eigen::Index w = std::max<Eigen::Index>(0, static_cast<Eigen::Index>(std::lround(0.5 * smooth * rate)));
  if (w == 0 || n == 0)
  {
    return x;
  }
  Eigen::MatrixXd cs = Eigen::MatrixXd::Zero(n + 1, x.cols());
  for (Eigen::Index i = 0; i < n; ++i)
  {
    cs.row(i + 1) = cs.row(i) + x.row(i);
  }
  Eigen::MatrixXd out(n, x.cols());
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const Eigen::Index a = std::max<Eigen::Index>(0, i - w), b = std::min(n, i + w + 1);
    out.row(i) = (cs.row(b) - cs.row(a)) / static_cast<double>(b - a);
  }
  return out;
}

Eigen::MatrixXd idealFromTruth(const TruthTrack& tr, const std::vector<double>& stamps, double gravity, double smooth)
{
  const std::size_t m = tr.size();
  if (m < 3 || tr.position.size() != m || tr.orientation.size() != m)
  {
    throw std::runtime_error("truth track too short or inconsistent (" + std::to_string(m) + " samples)");
  }
  // World velocity and body angular rate on the truth's time base.
  std::vector<Eigen::Vector3d> vel(m), omega(m);
  if (tr.has_twist)
  {
    for (std::size_t i = 0; i < m; ++i)
    {
      vel[i] = tr.orientation[i] * tr.velocity[i];
      omega[i] = tr.angular_velocity[i];
    }
  }
  else
  {
    vel = differentiate(tr.position, tr.stamp);
    for (std::size_t i = 0; i < m; ++i)
    {
      const std::size_t a = i > 0 ? i - 1 : 0, b = std::min(m - 1, i + 1);
      const double dt = tr.stamp[b] - tr.stamp[a];
      const Eigen::AngleAxisd rot(tr.orientation[a].conjugate() * tr.orientation[b]);  // body frame
      omega[i] = dt > 0 ? Eigen::Vector3d(rot.axis() * rot.angle() / dt) : Eigen::Vector3d::Zero();
    }
  }
  const std::vector<Eigen::Vector3d> acc = differentiate(vel, tr.stamp);
  Eigen::MatrixXd ao(m, 6);
  for (std::size_t i = 0; i < m; ++i)
  {
    ao.row(i).head<3>() = acc[i].transpose();
    ao.row(i).tail<3>() = omega[i].transpose();
  }
  const double truth_rate = (m - 1) / std::max(1e-9, tr.stamp.back() - tr.stamp.front());
  ao = movingAverage(ao, truth_rate, smooth);
  // Interpolated to the stamps; specific force through the interpolated attitude.
  Eigen::MatrixXd out(stamps.size(), kChannels);
  std::size_t j = 0;
  for (std::size_t k = 0; k < stamps.size(); ++k)
  {
    j = advance(tr.stamp, stamps[k], j);
    const std::size_t j1 = std::min(m - 1, j + 1);
    const double span = tr.stamp[j1] - tr.stamp[j];
    const double u = span > 0 ? std::clamp((stamps[k] - tr.stamp[j]) / span, 0.0, 1.0) : 0.0;
    sim::Truth t;
    t.acceleration = (1 - u) * ao.row(j).head<3>().transpose() + u * ao.row(j1).head<3>().transpose();
    t.angular_rate = (1 - u) * ao.row(j).tail<3>().transpose() + u * ao.row(j1).tail<3>().transpose();
    t.attitude = tr.orientation[j].slerp(u, tr.orientation[j1]);
    sim::Vector3 a, g;
    sim::idealImu(t, gravity, &a, &g);
    out.row(k).head<3>() = a.transpose();
    out.row(k).tail<3>() = g.transpose();
  }
  return out;
}

Eigen::MatrixXd truthResidual(const Recording& r, double gravity, double smooth)
{
  const double rate = r.rate > 0 ? r.rate : estimateRate(r);
  return movingAverage(r.data, rate, smooth) - idealFromTruth(r.truth, r.stamp, gravity, smooth);
}

std::vector<double> truthFeatures(const Eigen::MatrixXd& residual, int segments)
{
  std::vector<double> f;
  const Eigen::Index n = residual.rows();
  for (int c = 0; c < kChannels; ++c)
  {
    std::vector<double> sd;
    for (int s = 0; s < segments; ++s)
    {
      const Eigen::Index a = n * s / segments, b = n * (s + 1) / segments;
      const Eigen::VectorXd x = residual.col(c).segment(a, std::max<Eigen::Index>(1, b - a));
      const double mean = x.mean();
      f.push_back(mean);
      sd.push_back(std::sqrt((x.array() - mean).square().sum() / std::max<Eigen::Index>(1, x.size() - 1)));
    }
    f.insert(f.end(), sd.begin(), sd.end());
  }
  return f;
}

FeatureInfo segmentInfo(const std::string& channel, const std::string& quantity, const std::string& stage,
                        double duration, int s, int segments)
{
  FeatureInfo f;
  f.channel = channel;
  f.quantity = quantity;
  f.lo = duration * s / segments;
  f.hi = duration * (s + 1) / segments;
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.4g-%.4g s", f.lo, f.hi);
  f.range = buf;
  f.segment = "seg " + std::to_string(s + 1) + "/" + std::to_string(segments);
  f.stage = stage;
  return f;
}

FeatureLayout truthLayout(double duration, int segments)
{
  FeatureLayout L;
  L.segments = segments;
  for (int c = 0; c < kChannels; ++c)
  {
    const bool acc = c < 3;
    for (const std::string q : { "truth_mean", "truth_std" })
    {
      for (int s = 0; s < segments; ++s)
      {
        FeatureInfo f = segmentInfo(channelNames()[c], q, "truth", duration, s, segments);
        f.floor = q == "truth_mean" ? (acc ? 1e-5 : 1e-7) : (acc ? 1e-6 : 1e-8);
        f.rel_floor = q == "truth_mean" ? 0.0 : 0.03;
        L.info.push_back(f);
      }
    }
  }
  return L;
}
}  // namespace periodic_bias_compensation::gap
