// The motion stage of the diagnosis: the recording's standing tilt, heading and sea state
// against the scenario's, and the scenario refitted to them before any sensor effect is judged.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/gap/motion.h"
#include "periodic_bias_compensation/gap/signal.h"

namespace periodic_bias_compensation::gap
{
namespace
{
/// The wave band of the sea-state estimate [Hz]: periods of 2 to 25 s.
constexpr double kWaveBandLow = 0.04;
constexpr double kWaveBandHigh = 0.5;
/// Segments of the heave spectrum [s]: a quarter of the recording, from four times the longest
/// wave period of the band to 400 s (0.0025 Hz bins for a long swell).
constexpr double kMinWaveSegment = 100.0;
constexpr double kMaxWaveSegment = 400.0;
/// Below this the recording holds no sea worth a comparison [m].
constexpr double kMinWaveHeight = 0.05;
/// A quantity differs when the relative difference exceeds this and three ensemble spreads.
constexpr double kSeaTolerance = 0.15;
/// The largest response factor a fit gives a degree of freedom [-].
constexpr double kMaxResponse = 5.0;
/// The band of the short-wave fit [Hz]: above the wave peak of a wind sea, below the sensor's
/// own high-frequency effects; and the longest length it tries [m].
constexpr double kShortWaveLow = 0.3;
constexpr double kShortWaveHigh = 2.0;
constexpr double kMaxLength = 300.0;
/// Fewest spectrum bins the short-wave fit needs [-].
constexpr std::size_t kMinShortWaveBins = 8;
/// Median difference of log power [-] (natural log) between the recording's and the scenario's
/// short waves below which they agree: a factor e, far beyond what a sea state's height or
/// period off by 15 % makes of a JONSWAP tail.
constexpr double kShortWaveMisfit = 1.0;
/// A standing tilt or heading differs beyond this and three ensemble spreads [rad].
constexpr double kAngleTolerance = 0.005;
constexpr double kHeadingTolerance = 0.05;

struct Spread
{
  double mean = 0.0;
  double sd = 0.0;
};

template <class F>
Spread spreadOf(const std::vector<MotionSummary>& runs, F quantity)
{
  Spread s;
  for (const MotionSummary& m : runs)
    s.mean += quantity(m);
  s.mean /= std::max<std::size_t>(runs.size(), 1);
  for (const MotionSummary& m : runs)
    s.sd += std::pow(quantity(m) - s.mean, 2);
  s.sd = runs.size() > 1 ? std::sqrt(s.sd / (runs.size() - 1)) : 0.0;
  return s;
}

std::string format(const char* pattern, double a, double b)
{
  char text[200];
  std::snprintf(text, sizeof text, pattern, a, b);
  return text;
}

/// The mean of the runs' heave spectra (bin by bin; the runs share a length and a rate).
std::vector<double> meanHeaveDensity(const std::vector<MotionSummary>& runs)
{
  std::vector<double> mean(runs.empty() ? 0 : runs.front().heave_density.size(), 0.0);
  for (const MotionSummary& m : runs)
    for (std::size_t k = 0; k < mean.size() && k < m.heave_density.size(); ++k)
      mean[k] += m.heave_density[k] / runs.size();
  return mean;
}

bool hasSea(const sim::Scenario& s)
{
  return (s.motion.type == sim::MotionType::kSea || s.motion.type == sim::MotionType::kRoute) &&
         !s.motion.sea.systems.empty();
}
}  // namespace

MotionSummary summariseMotion(const Recording& r)
{
  MotionSummary m;
  const Eigen::Index n = r.data.rows();
  if (n < 2)
    return m;
  // Standing tilt: the mean of up in the sensor frame, as the reported orientation gives it;
  // without one, the mean specific force (which an accelerometer bias also moves: with an
  // orientation, that difference is left to the sensor effects).
  const Eigen::Vector3d mean_force = r.data.leftCols(3).colwise().mean().transpose();
  const bool oriented = r.has_orientation && r.orientation.size() == static_cast<std::size_t>(n);
  Eigen::Vector3d up_in_sensor = mean_force;
  if (oriented)
  {
    up_in_sensor.setZero();
    for (Eigen::Index i = 0; i < n; ++i)
      up_in_sensor += r.orientation[i].conjugate() * Eigen::Vector3d::UnitZ();
  }
  m.roll = std::atan2(up_in_sensor.y(), up_in_sensor.z());
  m.pitch = std::atan2(-up_in_sensor.x(), std::hypot(up_in_sensor.y(), up_in_sensor.z()));
  // Vertical specific force: through the reported orientation when there is one, else along
  // the mean force; gravity (its mean) taken off.
  const Eigen::Vector3d up = mean_force.normalized();
  Eigen::VectorXd vertical(n);
  Eigen::MatrixXd world(oriented ? n : 0, 2);  // horizontal specific force, ENU
  Eigen::Vector2d heading = Eigen::Vector2d::Zero();
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const Eigen::Vector3d f = r.data.row(i).head<3>().transpose();
    if (oriented)
    {
      const Eigen::Vector3d w = r.orientation[i] * f;
      vertical[i] = w.z();
      world.row(i) = w.head<2>().transpose();
      const Eigen::Vector3d x_axis = r.orientation[i] * Eigen::Vector3d::UnitX();
      heading += Eigen::Vector2d(x_axis.x(), x_axis.y());
    }
    else
      vertical[i] = f.dot(up);
  }
  vertical.array() -= vertical.mean();
  if (oriented)
    m.heading = std::atan2(heading.y(), heading.x());
  const double rate = r.rate > 0.0 ? r.rate : estimateRate(r);
  const double duration = n / std::max(rate, 1e-9);
  const double seconds = std::clamp(0.25 * duration, kMinWaveSegment, kMaxWaveSegment);
  const int segment = std::min<int>(static_cast<int>(n), static_cast<int>(std::lround(seconds * rate)));
  if (rate <= 0.0 || segment < 64 || segment * 1.0 / rate < 1.0 / kWaveBandLow)
    return m;
  // Heave spectrum = acceleration spectrum / (2 pi f)^4 over the wave band. The peak frequency
  // is the centroid of the spectrum to the fourth power: the top of a single peak, the middle of
  // a broad plateau whose highest bin wanders with the resolution (Young 1995).
  const Psd psd = welch(vertical, rate, segment);
  m.vertical_df = psd.df;
  m.vertical_density = psd.power;
  // Wave-band RMS per degree of freedom: the horizontal specific force along and across the mean
  // heading (world frame: no gravity in it), else the sensor's x and y; the gyro's three axes.
  const auto band_rms = [&](const Eigen::VectorXd& x) {
    const Psd p = welch(x.array() - x.mean(), rate, segment);
    double power = 0.0;
    for (std::size_t k = 1; k < p.power.size(); ++k)
      if (k * p.df >= kWaveBandLow && k * p.df <= kWaveBandHigh)
        power += p.power[k] * p.df;
    return std::sqrt(power);
  };
  if (oriented)
  {
    const double c = std::cos(m.heading), s = std::sin(m.heading);
    m.wave_rms[0] = band_rms(c * world.col(0) + s * world.col(1));
    m.wave_rms[1] = band_rms(-s * world.col(0) + c * world.col(1));
  }
  else
  {
    m.wave_rms[0] = band_rms(r.data.col(0));
    m.wave_rms[1] = band_rms(r.data.col(1));
  }
  m.wave_rms[2] = band_rms(vertical);
  for (int axis = 0; axis < 3; ++axis)
    m.wave_rms[3 + axis] = band_rms(r.data.col(3 + axis));
  double m0 = 0.0, s4 = 0.0, f_s4 = 0.0;
  for (std::size_t k = 1; k < psd.power.size(); ++k)
  {
    const double f = k * psd.df;
    if (f < kWaveBandLow || f > kWaveBandHigh)
      continue;
    const double heave = psd.power[k] / std::pow(2.0 * M_PI * f, 4);
    m.heave_frequency.push_back(f);
    m.heave_density.push_back(heave);
    m0 += heave * psd.df;
    s4 += std::pow(heave, 4);
    f_s4 += f * std::pow(heave, 4);
  }
  m.wave_height = 4.0 * std::sqrt(m0);
  if (s4 > 0.0 && f_s4 > 0.0)
    m.peak_period = s4 / f_s4;
  return m;
}

MotionFit fitMotion(const MotionSummary& real, const sim::Scenario& scenario, const std::vector<MotionSummary>& sims)
{
  MotionFit fit;
  fit.fitted = scenario;
  fit.real = real;
  if (sims.empty())
    return fit;
  const Spread roll = spreadOf(sims, [](const MotionSummary& m) { return m.roll; });
  const Spread pitch = spreadOf(sims, [](const MotionSummary& m) { return m.pitch; });
  const Spread height = spreadOf(sims, [](const MotionSummary& m) { return m.wave_height; });
  const Spread period = spreadOf(sims, [](const MotionSummary& m) { return m.peak_period; });
  fit.scenario.roll = roll.mean;
  fit.scenario.pitch = pitch.mean;
  fit.scenario.wave_height = height.mean;
  fit.scenario.peak_period = period.mean;
  fit.scenario.heave_frequency = sims.front().heave_frequency;
  fit.scenario.heave_density = meanHeaveDensity(sims);
  const auto beyond = [](double real_value, const Spread& s, double tolerance) {
    return std::abs(real_value - s.mean) > std::max(tolerance, 3.0 * s.sd);
  };

  sim::Scenario attitude = scenario, sea = scenario;
  bool attitude_differs = false, sea_fittable = false;
  // Standing tilt: a trim, a list or the mounting, not a sensor bias.
  if (beyond(fit.real.roll, roll, kAngleTolerance) || beyond(fit.real.pitch, pitch, kAngleTolerance))
  {
    fit.findings.push_back(
        format("standing tilt: roll %+.4f, pitch %+.4f rad", fit.real.roll, fit.real.pitch) +
        format(" against %+.4f, %+.4f in the scenario (a trim, list or mounting)", roll.mean, pitch.mean));
    attitude.motion.roll += fit.real.roll - roll.mean;
    attitude.motion.pitch += fit.real.pitch - pitch.mean;
    attitude_differs = true;
  }
  if (std::isfinite(fit.real.heading))
  {
    const Spread heading =
        spreadOf(sims, [](const MotionSummary& m) { return std::isfinite(m.heading) ? m.heading : 0.0; });
    fit.scenario.heading = heading.mean;
    const double turn = wrapAngle(fit.real.heading - heading.mean);
    if (std::abs(turn) > std::max(kHeadingTolerance, 3.0 * heading.sd) &&
        scenario.motion.type != sim::MotionType::kRoute)
    {
      fit.findings.push_back(format("heading %+.3f rad against %+.3f in the scenario", fit.real.heading, heading.mean));
      attitude.motion.heading = wrapAngle(attitude.motion.heading + turn);
      attitude_differs = true;
    }
  }

  // Sea state: significant height and peak period of the heave, each against the ensemble's.
  const bool real_sea = fit.real.wave_height > kMinWaveHeight;
  const bool scenario_sea = height.mean > kMinWaveHeight;
  if (real_sea || scenario_sea)
  {
    const double height_ratio = fit.real.wave_height / std::max(height.mean, 1e-9);
    const bool height_differs = std::abs(std::log(std::max(height_ratio, 1e-9))) > std::log1p(kSeaTolerance) &&
                                beyond(fit.real.wave_height, height, 0.0);
    const bool period_differs = real_sea && scenario_sea &&
                                std::abs(fit.real.peak_period / period.mean - 1.0) > kSeaTolerance &&
                                beyond(fit.real.peak_period, period, 0.0);
    if (height_differs || period_differs)
    {
      fit.differs = true;
      fit.findings.push_back(
          format("sea state: heave Hs %.3g m, peak period %.3g s", fit.real.wave_height, fit.real.peak_period) +
          format(" against Hs %.3g m, %.3g s in the scenario", height.mean, period.mean));
      if (hasSea(scenario) && real_sea && scenario_sea)
      {
        const double period_ratio = fit.real.peak_period / std::max(period.mean, 1e-9);
        if (period_ratio > 1.5 && height_ratio > 1.0)
        {
          // A swell the scenario lacks: the heave peaks far below the scenario's waves, which
          // keep their accelerations. A system at the recording's peak period makes up the
          // difference in heave variance.
          sim::WaveSystem swell = sea.motion.sea.systems.front();
          swell.peak_period = fit.real.peak_period;
          swell.significant_height = std::sqrt(std::pow(fit.real.wave_height, 2) - std::pow(height.mean, 2));
          sea.motion.sea.systems.push_back(swell);
        }
        else
        {
          // Every wave system scaled alike: the heave's Hs is linear in the systems' heights, its
          // peak period follows theirs.
          for (sim::WaveSystem& system : sea.motion.sea.systems)
          {
            system.significant_height *= height_ratio;
            system.peak_period *= period_ratio;
          }
        }
        sea_fittable = true;
      }
      else
        fit.findings.push_back(real_sea ? "the scenario has no sea to fit: give it one (motion type sea)"
                                        : "the recording shows no sea in the 2-25 s band");
    }
  }
  fit.differs = fit.differs || attitude_differs;
  // What to try, the whole fit first: each is adopted only if it brings the withheld part closer.
  if (attitude_differs && sea_fittable)
  {
    sim::Scenario both = sea;
    both.motion.roll = attitude.motion.roll;
    both.motion.pitch = attitude.motion.pitch;
    both.motion.heading = attitude.motion.heading;
    fit.candidates.push_back({ "tilt, heading and sea state", both });
  }
  if (attitude_differs)
    fit.candidates.push_back({ "tilt and heading", attitude });
  if (sea_fittable)
    fit.candidates.push_back({ "sea state", sea });
  return fit;
}

std::optional<MotionCandidate> fitWaveResponses(const MotionSummary& r, const sim::Scenario& scenario,
                                                const std::vector<MotionSummary>& sims,
                                                std::vector<std::string>* findings, bool rotations_only)
{
  if (!hasSea(scenario) || sims.empty())
    return std::nullopt;
  static const char* const kDof[6] = { "surge", "sway", "heave", "roll", "pitch", "yaw" };
  MotionCandidate candidate{ "wave responses", scenario };
  std::string changed;
  for (int d = 0; d < 6; ++d)
  {
    if (d == 2 || (rotations_only && d < 3))
      continue;  // the heave is the sea state's
    const Spread sim = spreadOf(sims, [d](const MotionSummary& m) { return m.wave_rms[d]; });
    const double ratio = r.wave_rms[d] / std::max(sim.mean, 1e-12);
    if (!(sim.mean > 0.0) || std::abs(std::log(std::max(ratio, 1e-9))) <= std::log1p(kSeaTolerance) ||
        std::abs(r.wave_rms[d] - sim.mean) <= 3.0 * sim.sd)
      continue;
    double& response = candidate.scenario.motion.sea.response[d];
    const double before = response;
    response = std::clamp(response * ratio, 0.0, kMaxResponse);
    changed += (changed.empty() ? "" : ", ") + std::string(kDof[d]) + " " + format("%.3g -> %.3g", before, response);
  }
  if (changed.empty())
    return std::nullopt;
  findings->push_back("wave responses (wave-band RMS per degree of freedom against the ensemble's): " + changed);
  return candidate;
}

std::optional<MotionCandidate> fitShortWaves(const MotionSummary& r, const sim::Scenario& scenario,
                                             const std::vector<MotionSummary>& sims, std::vector<std::string>* findings)
{
  if (!hasSea(scenario) || sims.empty() || r.vertical_density.empty() || !(r.vertical_df > 0.0))
    return std::nullopt;
  // The runs' mean spectrum, on the recording's bins (the runs share the recording's length and
  // rate, so their bins are the same).
  const std::size_t bins = r.vertical_density.size();
  std::vector<double> sim(bins, 0.0);
  for (const MotionSummary& m : sims)
  {
    if (m.vertical_density.size() != bins || std::abs(m.vertical_df - r.vertical_df) > 1e-9 * r.vertical_df)
      return std::nullopt;
    for (std::size_t k = 0; k < bins; ++k)
      sim[k] += m.vertical_density[k] / sims.size();
  }
  const double nyquist = (bins - 1) * r.vertical_df;
  const auto floorOf = [&](const std::vector<double>& density) {
    std::vector<double> top;
    for (std::size_t k = 0; k < bins; ++k)
      if (k * r.vertical_df >= 0.8 * nyquist)
        top.push_back(density[k]);
    return top.empty() ? 0.0 : upperMedian(top.begin(), top.end());
  };
  const double real_floor = floorOf(r.vertical_density), sim_floor = floorOf(sim);
  const double high = std::min(kShortWaveHigh, 0.8 * nyquist);
  // Per bin: the wavenumber (deep water), the recording's log power, the runs' motion above
  // their floor.
  struct Bin
  {
    double k, real, motion;
  };
  std::vector<Bin> used;
  const double g = scenario.gravity;
  for (std::size_t k = 1; k < bins; ++k)
  {
    const double f = k * r.vertical_df;
    if (f < kShortWaveLow || f > high)
      continue;
    if (r.vertical_density[k] > 10.0 * real_floor && sim[k] > 10.0 * sim_floor)
      used.push_back({ std::pow(2.0 * M_PI * f, 2) / g, std::log(r.vertical_density[k]), sim[k] - sim_floor });
  }
  if (used.size() < kMinShortWaveBins)
    return std::nullopt;
  // Power of a component of wavenumber k through a hull of length L: (1 + (L k / 2 pi)^2)^-2.
  const double given = scenario.motion.sea.length;
  const auto attenuation = [](double length, double k) {
    const double ratio = length * k / (2.0 * M_PI);
    return 1.0 / std::pow(1.0 + ratio * ratio, 2);
  };
  // |log power| differences per bin, and their sum (least absolute deviations: a few bins where
  // one spectrum ends, the simulator's highest wave component say, do not steer it).
  const auto residuals = [&](double length) {
    std::vector<double> out;
    for (const Bin& b : used)
      out.push_back(
          std::abs(b.real - std::log(b.motion * attenuation(length, b.k) / attenuation(given, b.k) + sim_floor)));
    return out;
  };
  const auto cost = [&](double length) {
    const std::vector<double> deviations = residuals(length);
    return std::accumulate(deviations.begin(), deviations.end(), 0.0);
  };
  std::vector<double> misfit = residuals(given);
  if (upperMedian(misfit.begin(), misfit.end()) <= kShortWaveMisfit)
    return std::nullopt;
  // A grid of lengths (every 0.5 m), then golden-section refinement around the best.
  double best = 0.0, best_cost = cost(0.0);
  for (double length = 0.5; length <= kMaxLength; length += 0.5)
  {
    const double c = cost(length);
    if (c < best_cost)
    {
      best_cost = c;
      best = length;
    }
  }
  double lo = std::max(0.0, best - 0.5), hi = std::min(kMaxLength, best + 0.5);
  const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int i = 0; i < 40; ++i)
  {
    const double a = hi - ratio * (hi - lo), b = lo + ratio * (hi - lo);
    if (cost(a) < cost(b))
      hi = b;
    else
      lo = a;
  }
  best = 0.5 * (lo + hi);
  if (std::abs(best - given) <= std::max(1.0, kSeaTolerance * given))
    return std::nullopt;
  MotionCandidate candidate{ "short waves", scenario };
  candidate.scenario.motion.sea.length = best;
  findings->push_back(format("short waves: the vertical spectrum over %.2g-%.2g Hz follows", kShortWaveLow, high) +
                      format(" a hull of length %.3g m against %.3g m in the scenario", best, given));
  return candidate;
}

std::string motionCsv(const MotionFit& fit, const std::vector<MotionSummary>& fitted)
{
  const std::vector<double> fitted_density = meanHeaveDensity(fitted);
  std::string csv = "f,real,given,fitted\n";
  const std::vector<double>& f = fit.real.heave_frequency;
  for (std::size_t k = 0; k < f.size(); ++k)
  {
    const auto at = [k](const std::vector<double>& v) { return k < v.size() ? v[k] : NAN; };
    char row[160];
    std::snprintf(row, sizeof row, "%.6g,%.6g,%.6g,%.6g\n", f[k], fit.real.heave_density[k],
                  at(fit.scenario.heave_density), at(fitted_density));
    csv += row;
  }
  return csv;
}

}  // namespace periodic_bias_compensation::gap
