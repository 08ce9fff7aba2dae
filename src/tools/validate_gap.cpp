// validate_gap: the diagnosis checked on data whose effect is withheld. For every effect of the
// simulator's vocabulary, several motions (static, sinusoids, sea; seas written outside the
// simulator; a real buoy's recorded motion), sizes and seeds: make a "real" recording with that effect, hand diagnose() the scenario without it, and record whether
// the verdict names it and how far the gap shrinks on the withheld part. Cases without any
// withheld effect check that no confident verdict is given.
//
//   validate_gap [--small] [--seeds N] [--duration S] [--rate HZ] [--md FILE] [--json FILE] [--quiet]
//                [--effect NAME] [--motion static|sinusoids|sea|sea-other-noise|hull-foreign|buoy-replay] [--verbose]
//                [--bench-hours H] [--buoy CSV --buoy-scenario YAML]
//
// --md and --json are renamed into place when complete (tools/output_file.h).
// Exit status: 0 targets met, 3 targets missed (the tables are printed either way), 1 error,
// 2 wrong command line.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "periodic_bias_compensation/gap/csv.h"
#include "periodic_bias_compensation/gap/gap.h"
#include "periodic_bias_compensation/sim/effects.h"
#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/output_file.h"

namespace gap = periodic_bias_compensation::gap;
namespace pbc = periodic_bias_compensation;
namespace sim = periodic_bias_compensation::sim;

namespace
{
struct Options
{
  bool small = false;
  int seeds = 2;
  double duration = 300.0;
  bool duration_given = false;  ///< --duration given: the buoy's recording is cut to it too
  double rate = 50.0;
  std::string md;
  std::string json;
  bool quiet = false;
  bool verbose = false;
  std::string only_effect;
  std::string only_motion;
  double bench_hours = 0.0;
  std::string buoy;           ///< the moored buoy's recording (../shared/data/buoy_morro_bay)
  std::string buoy_scenario;  ///< its plausible scenario (config/scenarios/gap_buoy_morro_bay.yaml)
};

/// The scenario the diagnosis is given for a motion: "static", "sinusoids", or otherwise ("sea",
/// "hull") an irregular sea.
sim::Scenario baseScenario(const std::string& motion, double rate, double duration)
{
  sim::Scenario s;
  s.name = "validate_" + motion;
  s.rate = rate;
  s.duration = duration;
  s.temperature.enabled = true;
  s.temperature.mean = 20.0;
  s.temperature.amplitude = 6.0;
  s.temperature.period = duration;
  if (motion == "static")
  {
    s.motion.type = sim::MotionType::kStatic;
    s.motion.roll = 0.02;
    s.motion.pitch = -0.01;
  }
  else if (motion == "sinusoids")
  {
    s.motion.type = sim::MotionType::kSinusoids;
    s.motion.sinusoids[sim::kSurge] = { 0.5, 0.21, 0.0 };
    s.motion.sinusoids[sim::kSway] = { 0.3, 0.17, 0.5 };
    s.motion.sinusoids[sim::kHeave] = { 1.0, 0.11, 1.0 };
    s.motion.sinusoids[sim::kRoll] = { 0.10, 0.15, 0.3 };
    s.motion.sinusoids[sim::kPitch] = { 0.05, 0.13, 0.7 };
    s.motion.sinusoids[sim::kYaw] = { 0.03, 0.07, 0.2 };
  }
  else
  {
    s.motion.type = sim::MotionType::kSea;
    s.motion.sea.components = 60;
    sim::WaveSystem w;
    w.significant_height = 2.0;
    w.peak_period = 8.0;
    w.direction = 0.7;
    w.spreading = 0.2;
    s.motion.sea.systems.push_back(w);
  }
  sim::EffectSpec bias{ "constant_bias", true, {} };
  bias.params["accel"] = { 0.01, -0.005, 0.008 };
  bias.params["gyro"] = { 2e-4, -1e-4, 1.5e-4 };
  sim::EffectSpec noise{ "white_noise", true, {} };
  noise.params["accel_density"] = { 2e-3 };
  noise.params["gyro_density"] = { 1e-4 };
  s.effects = { bias, noise };
  return s;
}

/// The withheld effect at size factor k (1 = clearly present, 0.3 = small).
std::vector<sim::EffectSpec> withheldEffect(const std::string& name, double k, const sim::Scenario& base)
{
  sim::EffectSpec e{ name, true, {} };
  if (name == "lever_arm")
  {
    e.params["offset"] = { 2.0 * k, -1.0 * k, 3.0 * k };
  }
  else if (name == "misalignment")
  {
    e.params["accel"] = { 0, 0.02 * k, -0.015 * k, -0.02 * k, 0, 0.01 * k, 0.015 * k, -0.01 * k, 0 };
    e.params["gyro"] = { 0, 0.02 * k, 0.01 * k, -0.02 * k, 0, -0.015 * k, -0.01 * k, 0.015 * k, 0 };
  }
  else if (name == "scale_factor")
  {
    e.params["accel"] = { 0.03 * k, -0.02 * k, 0.025 * k };
    e.params["gyro"] = { -0.03 * k, 0.02 * k, 0.03 * k };
  }
  else if (name == "constant_bias")
  {
    e.params["accel"] = { 0.03 * k, -0.02 * k, 0.025 * k };
    e.params["gyro"] = { 1e-3 * k, -8e-4 * k, 6e-4 * k };
  }
  else if (name == "periodic_bias")
  {
    e.params["accel_amplitude"] = { 0.02 * k, 0.0, 0.015 * k };
    e.params["accel_period"] = { 23.0, 10.0, 23.0 };
    e.params["gyro_amplitude"] = { 0.0, 5e-4 * k, 0.0 };
    e.params["gyro_period"] = { 10.0, 31.0, 10.0 };
  }
  else if (name == "thermal_drift")
  {
    e.params["accel_coefficient"] = { 2e-3 * k, -1.5e-3 * k, 2.5e-3 * k };
    e.params["gyro_coefficient"] = { 5e-5 * k, 0.0, -4e-5 * k };
    e.params["reference_temperature"] = { base.temperature.mean };
  }
  else if (name == "bias_random_walk")
  {
    e.params["accel_density"] = { 2e-3 * k };
    e.params["gyro_density"] = { 1e-4 * k };
  }
  else if (name == "bias_instability")
  {
    e.params["accel_sigma"] = { 0.01 * k };
    e.params["gyro_sigma"] = { 5e-4 * k };
    e.params["correlation_time"] = { 20.0 };
  }
  else if (name == "vibration")
  {
    e.params["frequency"] = { 17.3 };
    e.params["accel_amplitude"] = { 0.03 * k, 0.02 * k, 0.05 * k };
    e.params["gyro_amplitude"] = { 2e-3 * k, 0.0, 1e-3 * k };
  }
  else if (name == "white_noise")
  {
    // a different size: the base noise plus as much again (k = 1) in variance
    e.params["accel_density"] = { 2e-3 * std::sqrt(1.0 + 3.0 * k) };
    e.params["gyro_density"] = { 1e-4 * std::sqrt(1.0 + 3.0 * k) };
  }
  else if (name == "saturation")
  {
    // limits inside the motion's range (set below from a run of the base)
  }
  else if (name == "quantization")
  {
    e.params["accel_step"] = { 0.02 * k };
    e.params["gyro_step"] = { 1e-3 * k };
  }
  else if (name == "gravity_leakage")
  {
    e.params["roll"] = { 0.01 * k };
    e.params["pitch"] = { -0.008 * k };
    e.params["yaw"] = { 0.0 };
  }
  else if (name == "timestamp_jitter")
  {
    e.params["sigma"] = { 0.1 * k / base.rate };
    e.params["offset"] = { 0.0 };
  }
  else if (name == "sample_hold")
  {
    // a sensor at half the polling rate (k = 1: half the samples repeat), or 85 % of it
    e.params["sensor_rate"] = { base.rate * (1.0 - 0.5 * k) };
  }
  else if (name == "dropouts")
  {
    e.params["probability"] = { 0.003 * k };
    e.params["burst_length"] = { 3.0 };
  }
  return { e };
}

/// Saturation limits just inside the motion of r (clips the top 2k % of one accel and one gyro axis).
sim::EffectSpec saturationFor(const gap::Recording& r, double k)
{
  std::vector<double> lim(6);
  for (int c = 0; c < 6; ++c)
  {
    lim[c] = 2.0 * r.data.col(c).cwiseAbs().maxCoeff() + 1.0;
  }
  // clip az (gravity axis) and the busiest gyro axis at their 100 - 2k percentile
  auto pct = [&r](int c, double p) {
    std::vector<double> a(r.size());
    for (std::size_t i = 0; i < r.size(); ++i)
    {
      a[i] = std::abs(r.data(i, c));
    }
    std::sort(a.begin(), a.end());
    return a[static_cast<std::size_t>(p * (a.size() - 1))];
  };
  lim[2] = pct(2, 1.0 - 0.02 * k);
  int gbest = 3;
  for (int c = 4; c < 6; ++c)
  {
    if (pct(c, 0.99) > pct(gbest, 0.99))
    {
      gbest = c;
    }
  }
  lim[gbest] = std::max(1e-6, pct(gbest, 1.0 - 0.02 * k));
  sim::EffectSpec e{ "saturation", true, {} };
  e.params["accel_limit"] = { lim[0], lim[1], lim[2] };
  e.params["gyro_limit"] = { lim[3], lim[4], lim[5] };
  return e;
}

/// Effects whose whole signal, in a motion, is exactly that of another effect (stated from the
/// physics, before any run): without rotation a lever arm adds nothing; at rest a scale factor
/// or misalignment acts on gravity only, which is a constant bias on those axes.
std::string sameSignal(const std::string& effect, const std::string& motion)
{
  if (motion == "static" && effect == "lever_arm")
  {
    return "no rotation: a lever arm adds nothing";
  }
  if (motion == "static" && (effect == "scale_factor" || effect == "misalignment"))
  {
    return "at rest: acts on gravity only, the same signal as a constant bias";
  }
  if (motion == "buoy-replay" && effect == "thermal_drift")
  {
    return "the recording has no temperature";
  }
  return "";
}

/// A-priori detectability, measured the same way for every case: how far the withheld effect
/// ALONE moves the withheld part's features, in units of the ensemble's own spread. The twin is
/// the same recording (same seed, so the same noise) without the effect; for every effect but
/// constant_bias, the effect's own per-axis mean over the recording is taken out first (that
/// part is a constant bias and identifies nothing else). Detectable when that shift passes the
/// same significance test as a gap: gap > 1.5 x the largest null gap (one ensemble member
/// against the rest) or a |z| > max(1.5 x the null's largest |z|, 6).
struct Detectability
{
  double gap = 0.0;    ///< gap of the effect's own shift
  double max_z = 0.0;  ///< largest |z| of that shift
  bool detectable = false;
};

Detectability effectShift(const gap::Recording& real, gap::Recording twin, const std::string& effect,
                          const gap::Report& rep, double fit_fraction)
{
  twin.rate = real.rate;
  gap::Recording shifted = real;
  if (effect != "constant_bias" && twin.size() == real.size())
  {
    const Eigen::RowVectorXd own_mean = (real.data - twin.data).colwise().mean();
    shifted.data.rowwise() -= own_mean;
  }
  const auto fe = gap::computeFeatures(gap::sliceFraction(shifted, fit_fraction, 1.0), rep.layout_held);
  const auto ft = gap::computeFeatures(gap::sliceFraction(twin, fit_fraction, 1.0), rep.layout_held);
  std::vector<double> z(fe.size());
  Detectability d;
  for (std::size_t i = 0; i < z.size(); ++i)
  {
    z[i] = (fe[i] - ft[i]) / rep.ens_held.spread[i];
    d.max_z = std::max(d.max_z, std::abs(z[i]));
  }
  d.gap = gap::gapOf(z);
  d.detectable =
      d.gap > 1.5 * rep.null_gap_held || d.max_z > std::max(1.5 * rep.null_max_z_held, 2.0 * gap::kZThreshold);
  return d;
}

std::vector<double> paramOf(const sim::Scenario& s, const std::string& effect, const std::string& key)
{
  for (const auto& e : s.effects)
  {
    if (e.name == effect && e.params.count(key) > 0)
    {
      return e.params.at(key);
    }
  }
  return { 0.0, 0.0, 0.0 };
}

/// Effects the foreign generator below writes.
const std::vector<std::string>& foreignEffects()
{
  static const std::vector<std::string> e = { "constant_bias", "periodic_bias",    "vibration",
                                              "white_noise",   "bias_random_walk", "quantization" };
  return e;
}

/// JONSWAP spectral density (gamma 3.3) at f [Hz] for the peak frequency fp [Hz], unscaled.
double jonswapDensity(double f, double fp)
{
  const double sigma = f <= fp ? 0.07 : 0.09;
  return std::pow(f, -5.0) * std::exp(-1.25 * std::pow(fp / f, 4.0)) *
         std::pow(3.3, std::exp(-std::pow(f - fp, 2.0) / (2.0 * sigma * sigma * fp * fp)));
}

/// Replaces the samples and reported orientation of r by those of a hull in a sea written here,
/// not by the simulator: long-crested JONSWAP components (gamma 3.3, 200 between 0.04 and
/// 0.5 Hz, random phases; Hs 1.5-2.5 m and Tp 7-11 s drawn from the seed), each degree of freedom
/// with a gain and a phase of its own per component (surge, sway, roll and pitch are not locked
/// to the heave as a wave slope would lock them), a yaw the sea induces (0.02 rad), a standing
/// list and trim of 0.01-0.03 rad either way and a heading drawn. The IMU sits at the hull's
/// reference point: specific force R^T (p'' + g z), body rate from the Euler angles' rates
/// (z-y-x), all derivatives analytic.
void hullMotion(std::uint64_t seed, gap::Recording* r)
{
  constexpr double kTwoPi = 2.0 * M_PI, kG = sim::kStandardGravity;
  std::mt19937_64 rng(seed * 2654435761ULL + 99);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double hs = 1.5 + u(rng), fp = 1.0 / (7.0 + 4.0 * u(rng));
  const double list = (u(rng) < 0.5 ? -1.0 : 1.0) * (0.01 + 0.02 * u(rng));
  const double trim = (u(rng) < 0.5 ? -1.0 : 1.0) * (0.01 + 0.02 * u(rng));
  const double heading = kTwoPi * u(rng) - M_PI;
  constexpr int kComponents = 200;
  constexpr int kDof = 6;  // surge, sway, heave, roll, pitch, yaw
  const double df = (0.5 - 0.04) / kComponents;
  std::vector<double> w(kComponents), density(kComponents);
  std::vector<std::array<double, kDof>> gain(kComponents), phase(kComponents);
  double m0 = 0.0;
  for (int k = 0; k < kComponents; ++k)
  {
    const double f = 0.04 + (k + u(rng)) * df;
    w[k] = kTwoPi * f;
    density[k] = jonswapDensity(f, fp);
    m0 += density[k] * df;
    const double slope = w[k] * w[k] / kG;  // wave slope per metre of amplitude [rad/m]
    gain[k] = { 0.3 + 0.3 * u(rng),           0.2 + 0.3 * u(rng),           1.0,
                (0.6 + 0.4 * u(rng)) * slope, (0.3 + 0.3 * u(rng)) * slope, 0.2 * slope };
    for (double& p : phase[k])
    {
      p = kTwoPi * u(rng);
    }
  }
  for (int k = 0; k < kComponents; ++k)
  {
    const double amplitude = std::sqrt(2.0 * density[k] * df * hs * hs / 16.0 / m0);  // Hs = 4 sqrt(m0)
    for (double& g : gain[k])
    {
      g *= amplitude;
    }
  }
  const double t0 = r->stamp.empty() ? 0.0 : r->stamp.front();
  for (std::size_t i = 0; i < r->size(); ++i)
  {
    const double t = r->stamp[i] - t0;
    std::array<double, kDof> value{}, rate{}, acceleration{};
    for (int k = 0; k < kComponents; ++k)
    {
      for (int d = 0; d < kDof; ++d)
      {
        const double s = std::sin(w[k] * t + phase[k][d]), c = std::cos(w[k] * t + phase[k][d]);
        value[d] += gain[k][d] * s;
        rate[d] += gain[k][d] * w[k] * c;
        acceleration[d] -= gain[k][d] * w[k] * w[k] * s;
      }
    }
    const double roll = list + value[3], pitch = trim + value[4], yaw = heading + value[5];
    const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
    const Eigen::Vector3d world(acceleration[0], acceleration[1], acceleration[2] + kG);
    r->data.row(i).head<3>() = (q.conjugate() * world).transpose();
    const double sr = std::sin(roll), cr = std::cos(roll), sp = std::sin(pitch), cp = std::cos(pitch);
    r->data(i, 3) = rate[3] - sp * rate[5];
    r->data(i, 4) = cr * rate[4] + sr * cp * rate[5];
    r->data(i, 5) = -sr * rate[4] + cr * cp * rate[5];
    if (r->has_orientation)
    {
      r->orientation[i] = q;
    }
  }
  r->truth = gap::TruthTrack();
}

/// A "real" recording made WITHOUT the simulator's sensor model or random streams: the
/// simulator's noise-free motion (another seed family; on a sea 3x as many wave components, so
/// the motion's details differ) or, with `hull`, the motion of hullMotion(), plus the
/// scenario's bias and white noise and the withheld effect, all written here with
/// std::mt19937_64 and std::normal_distribution. The same seed gives the same motion and noise
/// whatever the effect (the twin of the detectability test).
gap::Recording foreignRecording(const sim::Scenario& base, const std::string& effect, double k, std::uint64_t seed,
                                bool hull)
{
  sim::Scenario clean = base;
  clean.effects.clear();
  if (hull)
  {
    clean.motion = sim::Motion();  // static: only the stamps, orientation and temperature are kept
  }
  else if (clean.motion.type == sim::MotionType::kSea)
  {
    clean.motion.sea.components *= 3;
  }
  gap::Recording r = gap::simulateRecording(clean, 900000 + seed);
  if (hull)
  {
    hullMotion(seed, &r);
  }
  std::mt19937_64 noise_rng(seed * 7919 + 13), walk_rng(seed * 104729 + 7);
  std::normal_distribution<double> n01;
  const double dt = 1.0 / base.rate;
  const auto ab = paramOf(base, "constant_bias", "accel"), gb = paramOf(base, "constant_bias", "gyro");
  const double grow = effect == "white_noise" ? std::sqrt(1.0 + 3.0 * k) : 1.0;
  const double ad = paramOf(base, "white_noise", "accel_density")[0] * grow;
  const double gd = paramOf(base, "white_noise", "gyro_density")[0] * grow;
  const double two_pi = 2.0 * std::acos(-1.0);
  double walk[gap::kChannels] = { 0, 0, 0, 0, 0, 0 };
  for (std::size_t i = 0; i < r.size(); ++i)
  {
    const double t = r.stamp[i] - r.stamp[0];
    for (int c = 0; c < gap::kChannels; ++c)
    {
      const bool acc = c < 3;
      double v = r.data(i, c) + (acc ? ab[c] : gb[c - 3]) + (acc ? ad : gd) / std::sqrt(dt) * n01(noise_rng);
      if (effect == "constant_bias")
      {
        const double b[gap::kChannels] = { 0.03, -0.02, 0.025, 1e-3, -8e-4, 6e-4 };
        v += k * b[c];
      }
      else if (effect == "periodic_bias")
      {
        const double amp[gap::kChannels] = { 0.02, 0.0, 0.015, 0.0, 5e-4, 0.0 };
        const double period[gap::kChannels] = { 23.0, 10.0, 23.0, 10.0, 31.0, 10.0 };
        v += k * amp[c] * std::sin(two_pi * t / period[c] + 0.4 * c);
      }
      else if (effect == "vibration")
      {
        const double amp[gap::kChannels] = { 0.03, 0.02, 0.05, 2e-3, 0.0, 1e-3 };
        v += k * amp[c] * std::sin(two_pi * 17.3 * t + 0.3);
      }
      else if (effect == "bias_random_walk")
      {
        walk[c] += k * (acc ? 2e-3 : 1e-4) * std::sqrt(dt) * n01(walk_rng);
        v += walk[c];
      }
      else if (effect == "quantization")
      {
        const double q = k * (acc ? 0.02 : 1e-3);
        v = q * std::round(v / q);
      }
      r.data(i, c) = v;
    }
  }
  r.source = "foreign generator";
  return r;
}

/// The moored buoy's recording (MicroStrain 3DM-GX3, 10 Hz, with its own AHRS; ../shared/data/
/// buoy_morro_bay): stamps from GPS time of week (from 0), specific force in g and rate in its
/// z-down frame, its NED roll, pitch and yaw as the reported orientation (gap::CsvOptions::ned).
/// @throws std::runtime_error when the file cannot be read or lacks a column
gap::Recording readBuoy(const std::string& path)
{
  gap::CsvOptions csv;
  csv.path = path;
  csv.columns =
      "t=gps_tow_s,ax=accel_x_g,ay=accel_y_g,az=accel_z_g,gx=gyro_x_rad_s,gy=gyro_y_rad_s,gz=gyro_z_rad_s,"
      "roll=roll_rad,pitch=pitch_rad,yaw=yaw_rad";
  csv.accel_scale = sim::kStandardGravity;
  csv.ned = true;
  gap::Recording r;
  try
  {
    r = gap::readCsv(csv);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(std::string("--buoy: ") + e.what());
  }
  const double start = r.stamp.front();
  for (double& t : r.stamp)
  {
    t -= start;
  }
  r.rate = gap::estimateRate(r);
  return r;
}

/// Band of a replayed recording kept as its motion [Hz]: a moored buoy's wave motion lies below
/// 0.5 Hz; above 1 Hz its own sensor noise and vibration dominate (docs/gap.md, "Real
/// recordings").
constexpr double kReplayBand = 1.0;

/// x low-passed without phase: a second-order Butterworth low-pass at `corner` [Hz] run forward
/// and backward (fourth order in magnitude), each pass started in its steady state for its first
/// value (no start transient).
Eigen::VectorXd zeroPhaseLowPass(const Eigen::VectorXd& x, double rate, double corner)
{
  const double k = std::tan(M_PI * corner / rate), norm = 1.0 / (1.0 + std::sqrt(2.0) * k + k * k);
  const double b0 = k * k * norm, b1 = 2.0 * b0, b2 = b0;
  const double a1 = 2.0 * (k * k - 1.0) * norm, a2 = (1.0 - std::sqrt(2.0) * k + k * k) * norm;
  const auto pass = [&](Eigen::VectorXd v) {
    if (v.size() == 0)
    {
      return v;
    }
    double z1 = (1.0 - b0) * v[0], z2 = (b2 - a2) * v[0];
    for (Eigen::Index i = 0; i < v.size(); ++i)
    {
      const double in = v[i], out = b0 * in + z1;
      z1 = b1 * in - a1 * out + z2;
      z2 = b2 * in - a2 * out;
      v[i] = out;
    }
    return v;
  };
  const Eigen::VectorXd forward = pass(x);
  return pass(forward.reverse()).reverse();
}

/// A real recording's motion, to be replayed as truth: on uniform stamps at its rate, its specific
/// force and rate low-passed to kReplayBand without phase, its reported orientation as it is. A
/// moored buoy neither turns nor accelerates on average, so what says otherwise is the real
/// sensor's, not the motion's, and is taken off: the rate's mean (the gyro's bias) and the mean
/// specific force in the reported frame less `gravity` straight up (the accelerometer's bias and
/// its AHRS's tilt error, which a motion consistent with its orientation does not have). Without a
/// reported orientation the specific force is left as it is.
/// @throws std::runtime_error when the recording has no rate
gap::Recording recordedMotion(const gap::Recording& recording, double gravity)
{
  if (!(recording.rate > 0.0))
  {
    throw std::runtime_error("--buoy: no sample rate in the recording's stamps");
  }
  gap::Recording motion = recording;
  for (std::size_t i = 0; i < motion.size(); ++i)
  {
    motion.stamp[i] = recording.stamp.front() + static_cast<double>(i) / recording.rate;
  }
  for (Eigen::Index c = 0; c < motion.data.cols(); ++c)
  {
    motion.data.col(c) = zeroPhaseLowPass(recording.data.col(c), recording.rate, kReplayBand);
  }
  motion.data.rightCols<3>().rowwise() -= motion.data.rightCols<3>().colwise().mean();
  if (motion.has_orientation && motion.orientation.size() == motion.size() && motion.size() > 0)
  {
    Eigen::Vector3d level_mean = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < motion.size(); ++i)
    {
      level_mean += motion.orientation[i] * Eigen::Vector3d(motion.data.row(static_cast<Eigen::Index>(i)).head<3>());
    }
    level_mean /= static_cast<double>(motion.size());
    const Eigen::Vector3d excess = level_mean - Eigen::Vector3d(0.0, 0.0, gravity);
    for (std::size_t i = 0; i < motion.size(); ++i)
    {
      motion.data.row(static_cast<Eigen::Index>(i)).head<3>() -=
          (motion.orientation[i].conjugate() * excess).transpose();
    }
  }
  return motion;
}

/// The recorded motion replayed as truth under simulated sensor effects: each sample's specific
/// force, rate and orientation go through the simulator's effects (their own random streams from
/// `seed`) as if they were the ideal sensor's; the angular acceleration a lever arm needs is the
/// central difference of the recorded rate. Samples the effects drop are left out.
gap::Recording replayRecording(const gap::Recording& motion, const std::vector<sim::EffectSpec>& effects,
                               std::uint64_t seed)
{
  std::vector<std::unique_ptr<sim::Effect>> made;
  for (std::size_t i = 0; i < effects.size(); ++i)
  {
    made.push_back(sim::makeEffect(sim::completeEffect(effects[i]), seed * 131 + i, motion.rate));
  }
  gap::Recording r = motion;
  r.stamp.clear();
  r.orientation.clear();
  std::size_t kept = 0;
  const std::size_t n = motion.size();
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t before = i > 0 ? i - 1 : 0, after = std::min(n - 1, i + 1);
    const double span = motion.stamp[after] - motion.stamp[before];
    sim::Truth truth;
    truth.attitude = motion.orientation[i];
    truth.angular_rate = motion.data.row(static_cast<Eigen::Index>(i)).tail<3>().transpose();
    if (span > 0.0)
    {
      truth.angular_acceleration = (motion.data.row(static_cast<Eigen::Index>(after)).tail<3>() -
                                    motion.data.row(static_cast<Eigen::Index>(before)).tail<3>())
                                       .transpose() /
                                   span;
    }
    sim::EffectInput in;
    in.elapsed = motion.stamp[i] - motion.stamp[0];
    in.truth = &truth;
    sim::ImuOutput out;
    out.accel = motion.data.row(static_cast<Eigen::Index>(i)).head<3>().transpose();
    out.gyro = truth.angular_rate;
    out.orientation = truth.attitude;
    for (const auto& effect : made)
    {
      effect->apply(in, out);
    }
    if (out.dropped)
    {
      continue;
    }
    r.stamp.push_back(motion.stamp[i] + out.stamp_offset);
    r.orientation.push_back(out.orientation);
    r.data.row(static_cast<Eigen::Index>(kept)).head<3>() = out.accel.transpose();
    r.data.row(static_cast<Eigen::Index>(kept)).tail<3>() = out.gyro.transpose();
    ++kept;
  }
  r.data.conservativeResize(static_cast<Eigen::Index>(kept), gap::kChannels);
  r.source = "buoy replay";
  return r;
}

struct CaseResult
{
  std::string motion, effect, verdict;
  double size = 0, confidence = 0, shrink = 0, gap_before = 0, null_gap = 0, seconds = 0;
  int seed = 0;
  bool detectable = true;
  std::string why;          ///< why not detectable
  double effect_gap = 0.0;  ///< gap of the effect's own shift (Detectability)
  double effect_max_z = 0.0;
  bool motion_differs = false;  ///< the diagnosis's motion stage found the motion different
};

/// Speed: a sea recording of `hours` at 100 Hz with a withheld vibration, diagnosed against the
/// scenario without it (the recording is simulated in memory, no file I/O).
int bench(double hours)
{
  const sim::Scenario base = baseScenario("sea", 100.0, hours * 3600.0);
  sim::Scenario real_s = base;
  for (const auto& e : withheldEffect("vibration", 1.0, base))
  {
    real_s.effects.push_back(e);
  }
  const auto s0 = std::chrono::steady_clock::now();
  gap::Recording real = gap::simulateRecording(real_s, 4242);
  const double tsim = std::chrono::duration<double>(std::chrono::steady_clock::now() - s0).count();
  const gap::Report rep = gap::diagnose(real, base, gap::DiagnoseOptions());
  std::printf(
      "bench: %.3g h at 100 Hz (%zu samples): recording simulated in %.1f s, diagnosed in %.1f s (verdict %s, "
      "shrink %.0f %%)\n",
      hours, real.size(), tsim, rep.seconds, rep.verdict_effect.c_str(), 100 * rep.shrink_withheld);
  return 0;
}

/// Effects of the simulator's vocabulary the validation withholds.
const std::vector<std::string>& simulatorEffects()
{
  static const std::vector<std::string> e = {
    "lever_arm",        "misalignment",     "scale_factor",     "constant_bias", "periodic_bias", "thermal_drift",
    "bias_random_walk", "bias_instability", "vibration",        "white_noise",   "saturation",    "quantization",
    "gravity_leakage",  "sample_hold",      "timestamp_jitter", "dropouts"
  };
  return e;
}

/// The motions, sizes and seeds the validation runs.
struct Grid
{
  std::vector<std::string> motions;
  std::vector<double> sizes;
  int seeds = 0;
};

/// Every motion of the full form, in its order ("buoy-replay" only with --buoy).
const std::vector<std::string> kMotions = { "static",          "sinusoids",    "sea",
                                            "sea-other-noise", "hull-foreign", "buoy-replay" };

Grid caseGrid(const Options& opt)
{
  // "hull-foreign": a hull in a sea of hullMotion() (not the simulator's), against the sea scenario.
  // "sea-other-noise": the simulator's sea model, but "real" is written by foreignRecording()
  // (another noise generator, other wave components), for the effects it knows.
  // "buoy-replay": the recorded buoy's motion under simulated effects, against its plausible
  // scenario (only with --buoy).
  Grid grid = { { kMotions.begin(), kMotions.end() - 1 }, { 1.0, 0.3 }, opt.seeds };
  if (opt.small)
  {
    grid.motions = { "sinusoids", "sea-other-noise", "hull-foreign" };
    grid.sizes = { 1.0 };
    grid.seeds = 1;
  }
  if (!opt.buoy.empty())
  {
    grid.motions.push_back("buoy-replay");
  }
  if (!opt.only_motion.empty())
  {
    grid.motions = { opt.only_motion };
  }
  return grid;
}

/// Whether the motion is hullMotion()'s ("hull-foreign"; its scenario is the sea's).
bool isHull(const std::string& motion)
{
  return motion.rfind("hull", 0) == 0;
}

/// Whether foreignRecording() writes the "real" recording of a motion ("sea-other-noise",
/// "hull-foreign").
bool isForeign(const std::string& motion)
{
  return motion == "sea-other-noise" || isHull(motion);
}

/// One effect at one size, run on `seeds` seeds.
struct MotionCase
{
  std::string effect;
  double size = 0.0;
  int seeds = 1;
};

/// The cases of a motion, those without a withheld effect last: in the small form only vibration
/// on the motions written outside the simulator. A replayed recording as it is, without an effect,
/// is the same whatever the seed: one case on one seed; two cases on every seed otherwise.
std::vector<MotionCase> motionCases(const std::string& motion, bool small, const std::vector<double>& sizes, int seeds)
{
  const bool replay = motion == "buoy-replay";
  const bool outside = isForeign(motion) || replay;
  std::vector<MotionCase> cases;
  for (const auto& e : isForeign(motion) ? foreignEffects() : simulatorEffects())
  {
    for (double k : sizes)
    {
      if (!(outside && small && e != "vibration"))
      {
        cases.push_back({ e, k, seeds });
      }
    }
  }
  cases.push_back({ "none", 0.0, replay ? 1 : seeds });
  if (!small && !replay)
  {
    cases.push_back({ "none", 0.0, seeds });
  }
  return cases;
}

/// The scenario of the "real" recording: base with the withheld effect at size factor k.
sim::Scenario withheldScenario(const sim::Scenario& base, const std::string& effect, double k)
{
  sim::Scenario real_s = base;
  if (effect == "saturation")
  {
    real_s.effects.push_back(saturationFor(gap::simulateRecording(base, 777), k));
  }
  else if (effect == "white_noise")
  {
    real_s.effects.erase(std::remove_if(real_s.effects.begin(), real_s.effects.end(),
                                        [](const sim::EffectSpec& e) { return e.name == "white_noise"; }),
                         real_s.effects.end());
    for (const auto& e : withheldEffect(effect, k, base))
    {
      real_s.effects.push_back(e);
    }
  }
  else if (effect != "none")
  {
    for (const auto& e : withheldEffect(effect, k, base))
    {
      real_s.effects.push_back(e);
    }
  }
  return real_s;
}

/// One case: the effect withheld at size factor k from a motion's recording of a seed.
struct Case
{
  std::string motion;
  std::string effect;
  double k = 0.0;
  std::uint64_t seed = 0;
};

/// The diagnosis' figures in cr: its verdict, and the shrink of the named effect, or of the
/// withheld effect's candidate when another was named.
void takeReport(const gap::Report& rep, CaseResult* cr)
{
  cr->verdict = rep.verdict_effect;
  cr->confidence = rep.confidence;
  cr->motion_differs = rep.motion.differs;
  cr->gap_before = rep.gap_before;
  cr->null_gap = rep.null_gap_held;
  cr->seconds = rep.seconds;
  cr->shrink = rep.shrink_withheld;
  for (const auto& c : rep.ranking)
  {
    if (c.effect == cr->effect)
    {
      cr->shrink = std::max(cr->shrink, c.shrink);
    }
  }
  if (rep.verdict_effect == "no_gap" || rep.verdict_effect == "none")
  {
    cr->shrink = rep.shrink_withheld;
    for (const auto& c : rep.ranking)
    {
      if (c.effect == cr->effect)
      {
        cr->shrink = c.shrink;
      }
    }
  }
}

/// Simulates the case's "real" recording, diagnoses it against base and scores the verdict (an
/// error of the diagnosis is the verdict "error: ...").
CaseResult runCase(const Case& c, const sim::Scenario& base, const gap::Recording* replayed, bool verbose)
{
  const bool foreign = isForeign(c.motion);
  // the "real" recording of the case and its twin without the withheld effect
  const auto recording = [&](const std::string& effect, double k) {
    if (replayed)
    {
      // The scenario's own sensor effects and the withheld one.
      std::vector<sim::EffectSpec> effects;
      if (effect == "saturation")
      {
        effects = base.effects;
        effects.push_back(saturationFor(*replayed, k));
      }
      else
      {
        effects = withheldScenario(base, effect, k).effects;
      }
      return replayRecording(*replayed, effects, c.seed);
    }
    if (foreign)
    {
      return foreignRecording(base, effect, k, c.seed, isHull(c.motion));
    }
    return gap::simulateRecording(effect == "none" ? base : withheldScenario(base, effect, k), c.seed);
  };
  const gap::DiagnoseOptions dopt;
  CaseResult cr;
  cr.motion = c.motion;
  cr.effect = c.effect;
  cr.size = c.k;
  cr.seed = static_cast<int>(c.seed);
  cr.why = sameSignal(c.effect, c.motion);
  try
  {
    gap::Recording real = recording(c.effect, c.k);
    real.source = "validate " + c.motion + " " + c.effect;
    const gap::Report rep = gap::diagnose(real, base, dopt);
    if (c.effect != "none")
    {
      const gap::Recording twin = recording("none", 0.0);
      const Detectability d = effectShift(real, twin, c.effect, rep, dopt.fit_fraction);
      cr.effect_gap = d.gap;
      cr.effect_max_z = d.max_z;
      if (cr.why.empty() && !d.detectable)
      {
        cr.why = "the effect alone moves the withheld features within the ensemble's spread";
      }
    }
    cr.detectable = cr.why.empty();
    if (verbose)
    {
      std::cerr << gap::reportSummary(rep);
    }
    takeReport(rep, &cr);
  }
  catch (const std::exception& e)
  {
    cr.verdict = std::string("error: ") + e.what();
  }
  return cr;
}

/// Every case of the grid, each reported on stderr unless --quiet.
std::vector<CaseResult> runCases(const Options& opt, const Grid& grid)
{
  std::vector<CaseResult> results;
  int case_index = 0;
  std::optional<gap::Recording> buoy;
  for (const std::string& motion : grid.motions)
  {
    sim::Scenario base;
    if (motion == "buoy-replay")
    {
      if (opt.buoy.empty())
      {
        throw std::runtime_error("--motion buoy-replay needs --buoy and --buoy-scenario");
      }
      buoy = readBuoy(opt.buoy);
      if (opt.duration_given)
      {
        const double span = buoy->stamp.back() - buoy->stamp.front() + 1.0 / buoy->rate;
        buoy = gap::sliceFraction(*buoy, 0.0, opt.duration / span);
      }
      const sim::Scenario given = sim::loadScenario(opt.buoy_scenario);
      buoy = recordedMotion(*buoy, given.gravity);
      base = gap::matchScenario(given, *buoy);
    }
    else
    {
      base = baseScenario(motion.substr(0, motion.find('-')), opt.rate, opt.duration);
    }
    for (const auto& [effect, k, seeds] : motionCases(motion, opt.small, grid.sizes, grid.seeds))
    {
      if (!opt.only_effect.empty() && effect != opt.only_effect)
      {
        continue;
      }
      for (int sd = 0; sd < seeds; ++sd)
      {
        ++case_index;
        const Case c = { motion, effect, k, static_cast<std::uint64_t>(5000 + 37 * sd + case_index) };
        const CaseResult cr = runCase(c, base, motion == "buoy-replay" ? &*buoy : nullptr, opt.verbose);
        if (!opt.quiet)
        {
          std::fprintf(stderr,
                       "%-9s %-17s size %.1f seed %5d -> %-30s conf %.2f shrink %5.1f %% gap %.3g (null %.3g) "
                       "shift %.3g/%.3g%s %.1f s\n",
                       motion.c_str(), effect.c_str(), k, cr.seed, cr.verdict.c_str(), cr.confidence, 100 * cr.shrink,
                       cr.gap_before, cr.null_gap, cr.effect_gap, cr.effect_max_z,
                       cr.detectable ? "" : " (undetectable)", cr.seconds);
        }
        results.push_back(cr);
      }
    }
  }
  return results;
}

/// Whether the verdict names the withheld effect (alone, in a pair, or as its line twin
/// periodic_bias/vibration).
bool named(const CaseResult& c)
{
  const std::string& v = c.verdict;
  if (v == c.effect || v.rfind(c.effect + "+", 0) == 0 ||
      (v.size() > c.effect.size() && v.substr(v.size() - c.effect.size() - 1) == "+" + c.effect))
  {
    return true;
  }
  return false;
}

/// Per motion: detectable cases named and all detectable, the median shrink of those named, the
/// cases without a withheld effect and how many of them the motion stage found different.
struct MotionScore
{
  int det_ok = 0, det = 0, nulls = 0, null_differs = 0;
  std::vector<double> shrinks;
};

struct Scores
{
  int det = 0, det_ok = 0, nulls = 0, null_confident = 0;
  std::map<std::string, MotionScore> per_motion;
  std::vector<double> shrinks;                                  ///< sorted, of the cases named correctly
  std::map<std::string, std::pair<int, int>> per_effect;        ///< named, detectable cases
  std::map<std::string, std::map<std::string, int>> confusion;  ///< withheld effect -> verdict -> count
  double median_shrink = 0.0;
  double accuracy = 0.0;
  bool pass = false;
};

Scores score(const std::vector<CaseResult>& results)
{
  Scores s;
  for (const auto& c : results)
  {
    MotionScore& m = s.per_motion[c.motion];
    if (c.effect == "none")
    {
      ++s.nulls;
      ++m.nulls;
      m.null_differs += c.motion_differs ? 1 : 0;
      s.null_confident += (c.confidence >= 0.5) ? 1 : 0;
      s.confusion["none"][c.verdict] += 1;
      continue;
    }
    s.confusion[c.effect][c.verdict] += 1;
    if (!c.detectable)
    {
      continue;
    }
    ++s.det;
    const bool ok = named(c);
    s.det_ok += ok ? 1 : 0;
    s.per_effect[c.effect].first += ok ? 1 : 0;
    s.per_effect[c.effect].second += 1;
    ++m.det;
    m.det_ok += ok ? 1 : 0;
    if (ok)
    {
      s.shrinks.push_back(c.shrink);
      m.shrinks.push_back(c.shrink);
    }
  }
  std::sort(s.shrinks.begin(), s.shrinks.end());
  s.median_shrink = s.shrinks.empty() ? 0.0 : s.shrinks[s.shrinks.size() / 2];
  s.accuracy = s.det > 0 ? static_cast<double>(s.det_ok) / s.det : 0.0;
  s.pass = s.accuracy >= 0.9 && s.median_shrink >= 0.7 && s.null_confident == 0;
  return s;
}

/// The run and its scores: what ran, the accuracy, the shrink's quantiles and the detectability test.
std::string summaryMarkdown(const Options& opt, const Grid& grid, std::size_t cases, const Scores& s, double wall)
{
  std::ostringstream md;
  md << "validate_gap" << (opt.small ? " --small" : "") << ": " << cases << " cases (" << opt.duration << " s at "
     << opt.rate << " Hz each; motions";
  for (const auto& m : grid.motions)
  {
    md << " " << m;
  }
  md << "; sizes";
  for (double k : grid.sizes)
  {
    md << " " << k;
  }
  md << "; " << grid.seeds << " seed(s)";
  if (std::find(grid.motions.begin(), grid.motions.end(), "buoy-replay") != grid.motions.end())
  {
    md << "; buoy-replay at the recording's own rate, "
       << (opt.duration_given ? "its first " + std::to_string(static_cast<int>(opt.duration)) + " s" : "all of it");
  }
  md << "), wall " << static_cast<int>(wall) << " s\n\n";
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "named correctly: %d of %d detectable cases (%.1f %%); median shrink on withheld data (correctly "
                "named): %.1f %%; confident verdicts (>= 0.5) on %d cases without a withheld effect: %d\n\n",
                s.det_ok, s.det, 100 * s.accuracy, 100 * s.median_shrink, s.nulls, s.null_confident);
  md << buf;
  const std::vector<double>& shrinks = s.shrinks;
  auto quantile = [&shrinks](double p) {
    return shrinks.empty() ? 0.0 : shrinks[static_cast<std::size_t>(p * (shrinks.size() - 1))];
  };
  std::snprintf(buf, sizeof(buf),
                "shrink when named correctly: p10 %.0f %%, p25 %.0f %%, median %.0f %%, min %.0f %%\n\n",
                100 * quantile(0.1), 100 * quantile(0.25), 100 * quantile(0.5), 100 * quantile(0.0));
  md << buf;
  md << "Detectable (stated before the runs, the same test for every case): the withheld effect ALONE (real "
        "minus its same-seed twin without the effect, less the effect's own per-axis mean unless it is a "
        "constant_bias) moves the withheld part's features by a gap > 1.5 x the largest null gap or a |z| > "
        "max(1.5 x the null's largest |z|, 6), in the ensemble's own spread; and its signal is not, by physics, "
        "exactly another effect's in that motion.\n\n";
  return md.str();
}

/// The verdicts given when `effect` was withheld: "verdict count", comma-separated.
std::string verdictCounts(const Scores& s, const std::string& effect)
{
  std::ostringstream out;
  const auto verdicts = s.confusion.find(effect);
  if (verdicts == s.confusion.end())
  {
    return "";
  }
  bool first = true;
  for (const auto& [v, n] : verdicts->second)
  {
    out << (first ? "" : ", ") << v << " " << n;
    first = false;
  }
  return out.str();
}

/// The table of verdicts per withheld effect, the undetectable and the missed cases, and whether
/// the targets are met.
std::string casesMarkdown(const std::vector<CaseResult>& results, const Scores& s)
{
  std::ostringstream md;
  md << "| withheld effect | named / detectable | verdicts (count) |\n|---|---|---|\n";
  for (const auto& e : simulatorEffects())
  {
    const auto pe = s.per_effect.count(e) > 0 ? s.per_effect.at(e) : std::pair<int, int>(0, 0);
    md << "| " << e << " | " << pe.first << " / " << pe.second << " | " << verdictCounts(s, e) << " |\n";
  }
  md << "| none | - | " << verdictCounts(s, "none") << " |\n\n";
  md << "| motion | named / detectable | median shrink (named) | without an effect: motion found different |\n"
        "|---|---|---|---|\n";
  for (auto [motion, m] : s.per_motion)
  {
    std::sort(m.shrinks.begin(), m.shrinks.end());
    const double median = m.shrinks.empty() ? 0.0 : m.shrinks[m.shrinks.size() / 2];
    md << "| " << motion << " | " << m.det_ok << " / " << m.det << " | " << static_cast<int>(std::lround(100 * median))
       << " % | " << m.null_differs << " of " << m.nulls << " |\n";
  }
  md << "\nNot detectable (effect's own shift: gap, largest |z|):";
  char buf[512];
  for (const auto& c : results)
  {
    if (c.effect != "none" && !c.detectable)
    {
      std::snprintf(buf, sizeof(buf), "\n- %s, %s, size %.1f, seed %d: %s (shift gap %.3g, |z| %.3g; verdict %s)",
                    c.effect.c_str(), c.motion.c_str(), c.size, c.seed, c.why.c_str(), c.effect_gap, c.effect_max_z,
                    c.verdict.c_str());
      md << buf;
    }
  }
  md << "\n\nMissed (detectable, not named):";
  for (const auto& c : results)
  {
    if (c.effect != "none" && c.detectable && !named(c))
    {
      std::snprintf(buf, sizeof(buf),
                    "\n- %s, %s, size %.1f, seed %d: verdict %s (confidence %.2f, gap %.3g, null %.3g, "
                    "effect's own shift: gap %.3g, |z| %.3g)",
                    c.effect.c_str(), c.motion.c_str(), c.size, c.seed, c.verdict.c_str(), c.confidence, c.gap_before,
                    c.null_gap, c.effect_gap, c.effect_max_z);
      md << buf;
    }
  }
  md << "\n\n"
     << (s.pass ? "TARGETS MET" : "TARGETS MISSED")
     << " (>= 90 % of detectable cases named, median shrink >= 70 %, no confident verdict without a "
        "withheld effect)\n";
  return md.str();
}

/// The --json file: the scores and every case, indented by 2.
std::string resultsJson(const std::vector<CaseResult>& results, const Scores& s)
{
  nlohmann::ordered_json cases = nlohmann::ordered_json::array();
  for (const auto& c : results)
  {
    cases.push_back({ { "motion", c.motion },
                      { "effect", c.effect },
                      { "size", gap::sixDigits(c.size) },
                      { "seed", c.seed },
                      { "verdict", c.verdict },
                      { "confidence", gap::sixDigits(c.confidence) },
                      { "shrink", gap::sixDigits(c.shrink) },
                      { "gap_before", gap::sixDigits(c.gap_before) },
                      { "null_gap", gap::sixDigits(c.null_gap) },
                      { "detectable", c.detectable },
                      { "effect_gap", gap::sixDigits(c.effect_gap) },
                      { "effect_max_z", gap::sixDigits(c.effect_max_z) },
                      { "motion_differs", c.motion_differs } });
  }
  const nlohmann::ordered_json j = { { "accuracy", gap::sixDigits(s.accuracy) },
                                     { "median_shrink", gap::sixDigits(s.median_shrink) },
                                     { "null_confident", s.null_confident },
                                     { "cases", cases } };
  return j.dump(2) + "\n";
}

/// The validation (or --bench-hours), writing its tables to the outputs given.
int validate(const Options& opt, pbc::OutputFile* md_file, pbc::OutputFile* json_file)
{
  if (opt.bench_hours > 0)
  {
    return bench(opt.bench_hours);
  }
  const Grid grid = caseGrid(opt);
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<CaseResult> results = runCases(opt, grid);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Scores scores = score(results);
  const std::string md = summaryMarkdown(opt, grid, results.size(), scores, wall) + casesMarkdown(results, scores);
  std::cout << md;
  if (md_file)
  {
    md_file->commit(md);
  }
  if (json_file)
  {
    json_file->commit(resultsJson(results, scores));
  }
  return scores.pass ? 0 : 3;
}
}  // namespace

int main(int argc, char** argv)
{
  Options opt;
  pbc::CommandLine cli(
      "usage: validate_gap [--small] [--seeds N] [--duration S] [--rate HZ] [--md FILE] [--json FILE]\n"
      "                    [--quiet] [--verbose] [--effect NAME] [--motion NAME] [--bench-hours H]\n"
      "                    [--buoy CSV --buoy-scenario YAML]\n"
      "Withholds each named effect from a simulated 'real' recording, diagnoses the gap against the\n"
      "scenario without it and scores the verdicts (docs/gap.md). --bench-hours H times one diagnosis\n"
      "of H hours of 100 Hz data instead. --buoy adds the motion 'buoy-replay': the moored buoy's\n"
      "recorded motion (../shared/data/buoy_morro_bay, low-passed at 1 Hz, its mean rate and the\n"
      "mean specific force beyond gravity taken off: the real sensor's) under YAML's sensor\n"
      "effects and the withheld one, against YAML (all of it, or its first S seconds when\n"
      "--duration S is given).\n");
  cli.flag("--small", &opt.small)
      .integer("--seeds", &opt.seeds)
      .number("--duration", &opt.duration, &opt.duration_given)
      .number("--rate", &opt.rate)
      .text("--md", &opt.md)
      .text("--json", &opt.json)
      .flag("--quiet", &opt.quiet)
      .flag("--verbose", &opt.verbose)
      .text("--effect", &opt.only_effect)
      .text("--motion", &opt.only_motion)
      .number("--bench-hours", &opt.bench_hours)
      .text("--buoy", &opt.buoy)
      .text("--buoy-scenario", &opt.buoy_scenario);
  try
  {
    if (!cli.parse(argc, argv))
      return 0;
    if (opt.buoy.empty() != opt.buoy_scenario.empty())
      throw pbc::UsageError("--buoy and --buoy-scenario go together");
    if (!opt.only_motion.empty() && std::find(kMotions.begin(), kMotions.end(), opt.only_motion) == kMotions.end())
    {
      std::string known;
      for (const std::string& m : kMotions)
        known += (known.empty() ? "" : ", ") + m;
      throw pbc::UsageError("unknown --motion '" + opt.only_motion + "' (" + known + ")");
    }
    pbc::refuseOverwritingInputs({ { "--buoy", opt.buoy }, { "--buoy-scenario", opt.buoy_scenario } },
                                 { { "--md", opt.md }, { "--json", opt.json } });
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "validate_gap: " << e.what() << "\n" << cli.usage();
    return 2;
  }
  try
  {
    // Created before the run: an output that cannot be written is said at once.
    std::optional<pbc::OutputFile> md_file, json_file;
    if (!opt.md.empty())
      md_file.emplace(opt.md);
    if (!opt.json.empty())
      json_file.emplace(opt.json);
    return validate(opt, md_file ? &*md_file : nullptr, json_file ? &*json_file : nullptr);
  }
  catch (const std::exception& e)
  {
    std::cerr << "validate_gap: " << e.what() << "\n";
    return 1;
  }
}
