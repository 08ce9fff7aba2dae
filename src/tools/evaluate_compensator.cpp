// evaluate_compensator: runs the estimation core over simulated scenarios with known truth and
// prints the drift of each method (no ROS, no bag): plain double integration, a causal high-pass
// baseline in the style of x-io's oscillatory motion tracking, constant-bias compensation, the
// paper's periodic compensation and the project's default mode. With --estimate it also scores
// the odometry another estimator wrote to a bag for the same scenario and seed (scripts/bench.py).
//
//   evaluate_compensator --scenario config/scenarios/paper_bench.yaml
//       [--calibration-scenario config/scenarios/paper_static.yaml] [--seeds 5] [--settle 20]
//       [--estimate NAME=BAG_PATTERN]... [--markdown OUT.md] [--csv OUT.csv]
//
// OUT.md and OUT.csv are renamed into place when complete, never over an input
// (tools/output_file.h). Exit status: 0 success, 1 error, 2 wrong command line.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/gain_tuning.h"
#include "periodic_bias_compensation/sim/simulator.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/core_sample.h"
#include "periodic_bias_compensation/tools/metrics.h"
#include "periodic_bias_compensation/tools/output_file.h"

namespace pbc = periodic_bias_compensation;
namespace metrics = periodic_bias_compensation::metrics;
namespace sim = periodic_bias_compensation::sim;
using pbc::Vector3;

namespace
{
struct Options
{
  std::string scenario;
  std::string calibration_scenario;
  int seeds = 5;
  double settle = 20.0;
  double duration = 0.0;  ///< > 0: replaces the scenario's duration [s]
  std::string markdown;
  std::string csv;
  std::vector<std::pair<std::string, std::string>> estimates;  ///< name, bag pattern
};

const char* kUsage =
    "usage: evaluate_compensator --scenario FILE.yaml [--calibration-scenario STATIC.yaml]\n"
    "                            [--seeds N] [--settle S] [--duration S] [--estimate NAME=BAG_PATTERN]...\n"
    "                            [--markdown OUT.md] [--csv OUT.csv]\n"
    "Simulates the scenario N times (seeds 1..N) and reports, per method and axis, the slow-motion\n"
    "error after the run, the total position error after the run, and the wave RMS error after S\n"
    "seconds as a percentage of the true wave RMS and of the significant wave height Hs = 4 x the\n"
    "standard deviation of the true wave motion of that axis. With --calibration-scenario the constant bias\n"
    "of the 'constant' and 'paper' methods comes from a run of that (static) scenario, as in the\n"
    "paper; the default mode always calibrates itself from the data, causally. The slow-motion error\n"
    "is also reported at 60 s, 10 min and 30 min of data (--duration S runs the scenario for S s).\n"
    "Where the scenario mounts the IMU on a lever arm, the default mode is given it (lever_arm_x/y/z,\n"
    "as a user configures the installation); every method is scored on base_link's motion.\n"
    "A second table gives the default mode's period tracking per axis: time of the first lock, share\n"
    "of FFT hops locked after it, and the error of its dominant frequency against the dominant\n"
    "frequency of the true wave acceleration over the same window (median and 95th percentile).\n"
    "--estimate adds a method NAME scored on the odometry another estimator wrote for the same\n"
    "scenario and seed: BAG_PATTERN with {seed} replaced by the seed; its odometry/filtered is the\n"
    "slow motion (linearly interpolated to the samples) and its odometry/wave, if present, the\n"
    "wave motion (zero otherwise); positions as published (the estimator starts at zero).\n";

/// The options, or nothing after --help.
std::optional<Options> parse(int argc, char** argv)
{
  Options o;
  pbc::CommandLine cli(kUsage);
  cli.text("--scenario", &o.scenario)
      .text("--calibration-scenario", &o.calibration_scenario)
      .integer("--seeds", &o.seeds)
      .number("--settle", &o.settle)
      .number("--duration", &o.duration)
      .text("--markdown", &o.markdown)
      .text("--csv", &o.csv)
      .option("--estimate", [&o](const std::string& spec) {
        const auto eq = spec.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
          throw pbc::UsageError("--estimate takes NAME=BAG_PATTERN, got '" + spec + "'");
        o.estimates.emplace_back(spec.substr(0, eq), spec.substr(eq + 1));
      });
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if (o.scenario.empty())
    throw pbc::UsageError("--scenario is required");
  if (o.seeds < 1)
    throw pbc::UsageError("--seeds must be >= 1");
  if (o.duration < 0.0)
    throw pbc::UsageError("--duration must be > 0");
  return o;
}

std::vector<sim::Sample> simulate(const sim::Scenario& scenario, std::uint64_t seed)
{
  sim::Simulator simulator(scenario, seed);
  std::vector<sim::Sample> samples;
  samples.reserve(static_cast<std::size_t>(simulator.sampleCount()));
  sim::Sample s;
  while (simulator.next(&s))
    if (!s.dropped)
      samples.push_back(s);
  return samples;
}

/// The default mode's methods without the IMU's orientation (see main).
const char* const kFixedLevel = "default, no orientation: one level frame";
/// The default mode with heave from the harmonic model (heave_filter: false), without the
/// broadband estimate: kept in the tables to show what the heave filter changes.
const char* const kHarmonicHeave = "default, harmonic heave";
/// Not a method of the main table: the causal bound on the wave error (boundTable).
const char* const kBound = "causal bound";
const char* const kDefaultAfterSpan = "default, after the bound's span";
const char* const kGyroLevel = "default, no orientation: gyro attitude";
const char* const kGyroLevelBias = "default, no orientation: gyro attitude, gyro bias estimated";

/// A ship whose true slow motion stays within this of its start holds station (moored, at
/// anchor, drifting a little): only there is "paper tuned"'s tuning criterion meaningful [m].
constexpr double kStationRadius = 50.0;

/// Seed of the training run that "paper tuned" is tuned on: never among the evaluated seeds 1..N.
constexpr std::uint64_t kTrainingSeed = 1000;

/// Whether the compensator is handed the IMU's orientation or has to level the samples itself.
enum class Orientation
{
  kGiven,
  kWithheld,
};

/// The causal bound (metrics::causalBound) means something here: a sea met on one course (no
/// route's turns) and a run longer than settle + kBoundSpan, where the bound has its history.
bool boundGiven(const sim::Scenario& scenario, double settle)
{
  return scenario.motion.type != sim::MotionType::kRoute && scenario.duration > settle + metrics::kBoundSpan;
}

/// One method's errors; `period`, if given, receives the period tracking of the run, and
/// `after_span` the same run scored from settle + metrics::kBoundSpan.
metrics::Errors evaluate(const std::vector<sim::Sample>& samples, double rate, const pbc::CompensatorConfig& config,
                         const std::optional<Vector3>& bias, double settle, metrics::PeriodErrors* period = nullptr,
                         Orientation orientation = Orientation::kGiven, metrics::Errors* after_span = nullptr)
{
  pbc::Compensator compensator(config);
  compensator.setBackgroundDesigns(false);  // the same outputs, faster offline
  if (bias && !compensator.setConstantBias(*bias))
    throw std::runtime_error("the calibration scenario's constant bias is not finite or beyond " +
                             std::to_string(pbc::kMaxConstantBias) + " m/s^2");
  metrics::Scorer scorer(samples.front(), settle);
  metrics::Scorer span_scorer(samples.front(), settle + metrics::kBoundSpan);
  metrics::PeriodScorer period_scorer(config, rate);
  pbc::CompensatorOutput out;
  // Without the IMU's orientation nothing gives the heading (no magnetometer): the estimate's level
  // frame is turned once about z onto the truth's at the first sample, as Madgwick's is (bench).
  std::optional<pbc::Quaternion> turn;
  for (const auto& s : samples)
  {
    pbc::ImuSample imu = pbc::toImuSample(s);
    imu.has_orientation = orientation == Orientation::kGiven;
    if (pbc::producedOutput(compensator.addSample(imu, &out)) && orientation == Orientation::kWithheld)
    {
      if (!turn)
      {
        const Vector3 x = (s.orientation * out.orientation.conjugate()) * Vector3::UnitX();
        turn = pbc::Quaternion(Eigen::AngleAxisd(std::atan2(x.y(), x.x()), Vector3::UnitZ()));
      }
      out.position_filtered = *turn * out.position_filtered;
      out.position_wave = *turn * out.position_wave;
    }
    scorer.add(s, out.position_filtered, out.position_wave);
    if (after_span != nullptr)
      span_scorer.add(s, out.position_filtered, out.position_wave);
    if (period != nullptr)
      period_scorer.add(s, out);
  }
  if (period != nullptr)
    *period = period_scorer.finish();
  if (after_span != nullptr)
    *after_span = span_scorer.finish(samples.back(), out.position_filtered, out.position_wave);
  return scorer.finish(samples.back(), out.position_filtered, out.position_wave);
}

/// Positions of one odometry topic of a bag (recorded with or without a leading slash), in stamp order.
struct Track
{
  std::vector<double> t;
  std::vector<Vector3> p;

  /// Linear interpolation; held constant beyond the ends.
  Vector3 at(double time) const
  {
    const auto it = std::upper_bound(t.begin(), t.end(), time);
    if (it == t.begin())
      return p.front();
    if (it == t.end())
      return p.back();
    const std::size_t k = it - t.begin();
    const double w = (time - t[k - 1]) / (t[k] - t[k - 1]);
    return p[k - 1] + w * (p[k] - p[k - 1]);
  }
};

Track readTrack(const rosbag::Bag& bag, const std::string& topic)
{
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{ topic, "/" + topic }));
  std::vector<std::pair<double, Vector3>> points;
  for (const rosbag::MessageInstance& m : view)
    if (const auto odom = m.instantiate<nav_msgs::Odometry>())
    {
      const auto& q = odom->pose.pose.position;
      points.emplace_back(odom->header.stamp.toSec(), Vector3(q.x, q.y, q.z));
    }
  std::stable_sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  Track track;
  for (const auto& [t, p] : points)
    if (track.t.empty() || t > track.t.back())
    {
      track.t.push_back(t);
      track.p.push_back(p);
    }
  return track;
}

/// Another estimator's odometry for this run (slow motion on odometry/filtered, wave motion on
/// odometry/wave if the bag has it), scored like the methods above.
metrics::Errors scoreEstimate(const std::vector<sim::Sample>& samples, const std::string& path, double settle)
{
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  const Track slow = readTrack(bag, "odometry/filtered");
  const Track wave = readTrack(bag, "odometry/wave");
  if (slow.t.size() < 2)
    throw std::runtime_error(path + ": fewer than two odometry/filtered messages");
  const double end = samples.back().stamp, start = samples.front().stamp;
  const double period = (end - start) / (samples.size() - 1);
  if (slow.t.front() > start + settle || slow.t.back() < end - std::max(1.0, 2 * period))
    throw std::runtime_error(path + ": odometry/filtered covers " + std::to_string(slow.t.front()) + ".." +
                             std::to_string(slow.t.back()) + " s, the scenario " + std::to_string(start) + ".." +
                             std::to_string(end) + " s");
  auto waveAt = [&](double t) { return wave.t.empty() ? Vector3::Zero() : Vector3(wave.at(t)); };
  metrics::Scorer scorer(samples.front(), settle);
  for (const auto& s : samples)
    scorer.add(s, slow.at(s.stamp), waveAt(s.stamp));
  return scorer.finish(samples.back(), slow.at(end), waveAt(end));
}

/// The IMU's offset from base_link as the scenario installs it (its lever_arm effect), as a user
/// configures it (lever_arm_x/y/z): the estimators are scored on base_link's motion.
Vector3 installedLeverArm(const sim::Scenario& scenario)
{
  for (const auto& effect : scenario.effects)
    if (effect.name == "lever_arm" && effect.enabled)
    {
      const auto offset = effect.params.find("offset");
      if (offset != effect.params.end() && offset->second.size() == 3)
        return Vector3(offset->second[0], offset->second[1], offset->second[2]);
    }
  return Vector3::Zero();
}

std::string seedPath(std::string pattern, int seed)
{
  const std::string key = "{seed}";
  for (auto at = pattern.find(key); at != std::string::npos; at = pattern.find(key))
    pattern.replace(at, key.size(), std::to_string(seed));
  return pattern;
}

std::string format(double value, const char* spec)
{
  if (!std::isfinite(value))
    return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), spec, value);
  return buffer;
}

/// Paper Sec. 4.1: the constant bias from a recording at rest (a run of the scenario file given).
Vector3 staticBias(const std::string& calibration_scenario)
{
  pbc::CompensatorConfig config;
  config.mode = pbc::Mode::kPaper;
  config.assume_static_calibration = true;
  config.enable_periodic = false;
  const sim::Scenario rest = sim::loadScenario(calibration_scenario);
  // The whole recording is the window (its last sample is one period short of the duration).
  config.calibration_duration = rest.duration - 1.5 / rest.rate;
  pbc::Compensator calibration(config);
  for (const auto& s : simulate(rest, 1000))
    calibration.addSample(pbc::toImuSample(s), nullptr);
  if (!calibration.calibrated())
    throw std::runtime_error("the calibration scenario did not complete a calibration window");
  const Vector3 bias = calibration.constantBias();
  std::cerr << "constant bias from " << calibration_scenario << ": " << bias.transpose() << " m/s^2\n";
  return bias;
}

/// Paper mode, and paper mode with alpha/beta tuned automatically (tunePaperGains).
struct PaperConfigs
{
  pbc::CompensatorConfig paper;
  pbc::CompensatorConfig tuned;
  bool holds_station = false;  ///< whether the training run holds station (else nothing is tuned)
  std::string note;            ///< how the gains were tuned, or why they were not (after the table)
};

/// The note on the gains tunePaperGains found.
std::string tuningNote(const pbc::GainTuningResult& tuning)
{
  std::ostringstream note;
  note << "\n`paper tuned`: gains tuned on seed " << kTrainingSeed << " (slow-motion RMS there, x y z: ";
  for (int i = 0; i < 3; ++i)
    note << format(tuning.score_start[i], "%.4f") << " -> " << format(tuning.score[i], "%.4f") << (i < 2 ? ", " : " m");
  note << "); alpha_v beta_v alpha_p beta_p per axis:";
  for (int i = 0; i < 3; ++i)
    note << " "
         << "xyz"[i] << " " << tuning.gains[i].alpha_v << " " << tuning.gains[i].beta_v << " "
         << tuning.gains[i].alpha_p << " " << tuning.gains[i].beta_p << (i < 2 ? ";" : "\n");
  return note.str();
}

/// Paper mode's gains tuned on a training run of the same scenario whose seed is not among the
/// evaluated ones; the tuning's criterion takes the vessel as holding station (true slow motion
/// zero) and uses no truth.
PaperConfigs tunePaper(const sim::Scenario& scenario, const std::optional<Vector3>& calibrated_bias, double settle)
{
  PaperConfigs configs;
  configs.paper.mode = pbc::Mode::kPaper;
  configs.paper.assume_static_calibration = true;
  configs.tuned = configs.paper;
  const std::vector<sim::Sample> training_run = simulate(scenario, kTrainingSeed);
  double travelled = 0.0;  // farthest the true slow motion gets from its start [m]
  for (const auto& s : training_run)
    travelled = std::max(travelled, (s.truth.slow_position - training_run.front().truth.slow_position).norm());
  configs.holds_station = travelled <= kStationRadius;
  if (!configs.holds_station)
  {
    // A user tunes on a recording made while moored or at anchor; underway there is none.
    configs.note =
        "\n`paper tuned` is not run here: the tuning needs a recording made while holding station "
        "(its criterion takes the slow motion as zero), and this ship goes " +
        format(travelled, "%.0f") + " m from its start.\n";
    std::cerr << configs.note;
    return configs;
  }
  std::vector<pbc::ImuSample> training;
  for (const auto& s : training_run)
    training.push_back(pbc::toImuSample(s));
  const pbc::GainTuningResult tuning =
      pbc::tunePaperGains(training, configs.paper, calibrated_bias, settle, {}, 2, [](int done, int total) {
        std::cerr << "\rtuning paper gains on seed " << kTrainingSeed << ": run " << done << "/" << total << std::flush;
      });
  configs.tuned.gains = tuning.gains;
  configs.note = tuningNote(tuning);
  std::cerr << "\n" << configs.note;
  return configs;
}

/// What every seed's run is scored with.
struct Setup
{
  sim::Scenario scenario;
  std::optional<Vector3> calibrated_bias;  ///< from --calibration-scenario, if given
  PaperConfigs paper;
};

/// The methods in table order.
std::vector<std::string> methodNames(const Options& options, bool holds_station)
{
  std::vector<std::string> methods = { "raw",     "highpass",     "constant",  "paper",    "paper tuned",
                                       "default", kHarmonicHeave, kFixedLevel, kGyroLevel, kGyroLevelBias };
  if (!holds_station)
    methods.erase(std::find(methods.begin(), methods.end(), "paper tuned"));
  for (const auto& estimate : options.estimates)
    methods.push_back(estimate.first);
  return methods;
}

/// Per method, its errors of each seed; the default mode's period tracking of each seed.
struct Results
{
  std::map<std::string, std::vector<metrics::Errors>> errors;
  std::vector<metrics::PeriodErrors> periods;
};

/// Simulates one seed and scores every method on it.
void runSeed(const Setup& setup, const Options& options, int seed, Results* results)
{
  const sim::Scenario& scenario = setup.scenario;
  const std::optional<Vector3>& calibrated_bias = setup.calibrated_bias;
  std::map<std::string, std::vector<metrics::Errors>>& errors = results->errors;
  const auto samples = simulate(scenario, static_cast<std::uint64_t>(seed));
  if (samples.size() < 16)
    throw std::runtime_error("scenario produced too few samples");
  pbc::CompensatorConfig constant = setup.paper.paper;
  constant.enable_periodic = false;
  pbc::CompensatorConfig ours;
  ours.lever_arm = installedLeverArm(scenario);
  errors["raw"].push_back(metrics::integrateRaw(samples, pbc::kStandardGravity));
  errors["highpass"].push_back(metrics::highPassBaseline(samples, pbc::kStandardGravity, options.settle));
  errors["constant"].push_back(evaluate(samples, scenario.rate, constant, calibrated_bias, options.settle));
  errors["paper"].push_back(evaluate(samples, scenario.rate, setup.paper.paper, calibrated_bias, options.settle));
  if (setup.paper.holds_station)
    errors["paper tuned"].push_back(
        evaluate(samples, scenario.rate, setup.paper.tuned, calibrated_bias, options.settle));
  results->periods.emplace_back();
  // The default mode is also scored over the span where the causal bound has its history.
  const bool bound = boundGiven(scenario, options.settle);
  metrics::Errors after_span;
  errors["default"].push_back(evaluate(samples, scenario.rate, ours, std::nullopt, options.settle,
                                       &results->periods.back(), Orientation::kGiven, bound ? &after_span : nullptr));
  pbc::CompensatorConfig harmonic_heave = ours;
  harmonic_heave.heave_filter = false;
  errors[kHarmonicHeave].push_back(evaluate(samples, scenario.rate, harmonic_heave, std::nullopt, options.settle));
  // The same without the IMU's orientation: one level frame, or the gyro's attitude without
  // and with its bias estimated.
  pbc::CompensatorConfig fixed_level = ours;
  fixed_level.gyro_attitude = false;
  errors[kFixedLevel].push_back(
      evaluate(samples, scenario.rate, fixed_level, std::nullopt, options.settle, nullptr, Orientation::kWithheld));
  pbc::CompensatorConfig gyro = ours;
  gyro.gyro_attitude = true;
  gyro.estimate_gyro_bias = false;
  errors[kGyroLevel].push_back(
      evaluate(samples, scenario.rate, gyro, std::nullopt, options.settle, nullptr, Orientation::kWithheld));
  gyro.estimate_gyro_bias = true;
  errors[kGyroLevelBias].push_back(
      evaluate(samples, scenario.rate, gyro, std::nullopt, options.settle, nullptr, Orientation::kWithheld));
  for (const auto& [name, pattern] : options.estimates)
    errors[name].push_back(scoreEstimate(samples, seedPath(pattern, seed), options.settle));
  if (bound)
  {
    errors[kBound].push_back(metrics::causalBound(samples, pbc::kStandardGravity, options.settle, ours.lever_arm));
    errors[kDefaultAfterSpan].push_back(after_span);
  }
}

/// The error table, per method and axis the medians over seeds; `csv`, if open, receives every
/// seed's values.
std::string errorTable(const std::vector<std::string>& methods,
                       const std::map<std::string, std::vector<metrics::Errors>>& errors, std::ofstream* csv)
{
  std::ostringstream table;
  table << "| method | axis | slow-motion error at 60 s [m] | at 10 min [m] | at 30 min [m] | at end [m] "
           "| slow-motion RMS error [m] | total position error at end [m] | total position RMS error [m] "
           "| wave RMS error [% of true wave RMS] | wave RMS error [% of Hs] |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|\n";
  if (csv->is_open())
    *csv << "method,axis,seed,slow_60s_m,slow_10min_m,slow_30min_m,slow_final_m,slow_rms_m,total_final_m,"
            "total_rms_m,wave_rms_percent,wave_hs_percent\n";
  const char* axes = "xyz";
  for (const auto& method : methods)
    for (int i = 0; i < 3; ++i)
    {
      // Columns in table order; each holds one value per seed.
      std::array<std::vector<double>, 9> columns;
      const std::vector<metrics::Errors>& runs = errors.at(method);
      for (std::size_t k = 0; k < runs.size(); ++k)
      {
        const metrics::Errors& e = runs[k];
        const std::array<double, 9> row = { e.slow_at[0][i], e.slow_at[1][i],       e.slow_at[2][i],
                                            e.slow_final[i], e.slow_rms[i],         e.total_final[i],
                                            e.total_rms[i],  e.wave_rms_percent[i], e.wave_hs_percent[i] };
        if (csv->is_open())
          *csv << method << "," << axes[i] << "," << k + 1;
        for (std::size_t c = 0; c < row.size(); ++c)
        {
          columns[c].push_back(row[c]);
          if (csv->is_open())
            *csv << "," << row[c];
        }
        if (csv->is_open())
          *csv << "\n";
      }
      table << "| " << method << " | " << axes[i];
      for (std::size_t c = 0; c < columns.size(); ++c)
        table << " | " << format(metrics::median(columns[c]), c < 7 ? "%.4f" : (c == 7 ? "%.1f" : "%.2f"));
      table << " |\n";
    }
  return table.str();
}

/// The default mode's wave error against the causal bound (metrics::causalBound), medians over
/// seeds.
std::string boundTable(const std::map<std::string, std::vector<metrics::Errors>>& errors, const sim::Scenario& scenario,
                       double settle)
{
  std::ostringstream table;
  const double from = settle + metrics::kBoundSpan;
  if (!boundGiven(scenario, settle))
    return scenario.motion.type == sim::MotionType::kRoute
               ? "\nCausal bound on the wave error: not given (the route's turns change the sea as met; one filter "
                 "fitted to the whole run is no bound).\n"
               : "\nCausal bound on the wave error: not given (the run ends before " + format(from, "%.0f") +
                     " s, where the bound has its history).\n";
  table << "\nWave error against the causal bound, from " << format(from, "%.0f")
        << " s to the end: the best a causal linear filter of the axis's own level acceleration does there "
           "(through the spectral estimate's low-pass, "
        << format(metrics::kBoundStep, "%.2f") << " s; FIR of " << format(metrics::kBoundSpan, "%.0f")
        << " s, fitted by least squares to the truth of the other half of the run), and the default mode over "
           "the same span; medians over seeds:\n\n"
           "| axis | bound [% of true wave RMS] | default [% of true wave RMS] | bound [% of Hs] "
           "| default [% of Hs] |\n|---|---|---|---|---|\n";
  const char* axes = "xyz";
  for (int i = 0; i < 3; ++i)
  {
    std::array<std::vector<double>, 4> columns;
    for (const metrics::Errors& e : errors.at(kBound))
    {
      columns[0].push_back(e.wave_rms_percent[i]);
      columns[2].push_back(e.wave_hs_percent[i]);
    }
    for (const metrics::Errors& e : errors.at(kDefaultAfterSpan))
    {
      columns[1].push_back(e.wave_rms_percent[i]);
      columns[3].push_back(e.wave_hs_percent[i]);
    }
    table << "| " << axes[i] << " | " << format(metrics::median(columns[0]), "%.1f") << " | "
          << format(metrics::median(columns[1]), "%.1f") << " | " << format(metrics::median(columns[2]), "%.2f")
          << " | " << format(metrics::median(columns[3]), "%.2f") << " |\n";
  }
  return table.str();
}

/// Period tracking of the default mode (the paper mode uses the same tracker), medians over seeds.
std::string periodTable(const std::vector<metrics::PeriodErrors>& periods)
{
  std::ostringstream table;
  table << "\nPeriod tracking (default mode), medians over seeds:\n\n"
           "| axis | first lock [s] | FFT hops locked after it [%] | dominant-frequency error, median [%] "
           "| 95th percentile [%] |\n|---|---|---|---|---|\n";
  const char* axes = "xyz";
  for (int i = 0; i < 3; ++i)
  {
    std::array<std::vector<double>, 4> columns;
    int never = 0;
    for (const metrics::PeriodErrors& p : periods)
    {
      never += std::isnan(p.lock_time[i]) ? 1 : 0;
      const std::array<double, 4> row = { p.lock_time[i], p.locked_percent[i], p.error_median[i], p.error_p95[i] };
      for (std::size_t c = 0; c < row.size(); ++c)
        columns[c].push_back(row[c]);
    }
    table << "| " << axes[i] << " | " << format(metrics::median(columns[0]), "%.1f")
          << (never > 0 ? " (never in " + std::to_string(never) + " of " + std::to_string(periods.size()) + ")" : "")
          << " | " << format(metrics::median(columns[1]), "%.0f") << " | "
          << format(metrics::median(columns[2]), "%.2f") << " | " << format(metrics::median(columns[3]), "%.2f")
          << " |\n";
  }
  return table.str();
}
}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    const std::optional<Options> parsed = parse(argc, argv);
    if (!parsed)
      return 0;
    options = *parsed;
    std::vector<pbc::NamedPath> inputs = { { "--scenario", options.scenario },
                                           { "--calibration-scenario", options.calibration_scenario } };
    for (const auto& [name, pattern] : options.estimates)
      for (int seed = 1; seed <= options.seeds; ++seed)
        inputs.push_back({ "--estimate " + name, seedPath(pattern, seed) });
    pbc::refuseOverwritingInputs(inputs, { { "--markdown", options.markdown }, { "--csv", options.csv } });
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "evaluate_compensator: " << e.what() << "\n" << kUsage;
    return 2;
  }
  try
  {
    // Created before the runs: an output that cannot be written is said at once.
    std::optional<pbc::OutputFile> markdown_file, csv_file;
    if (!options.markdown.empty())
      markdown_file.emplace(options.markdown);
    if (!options.csv.empty())
      csv_file.emplace(options.csv);
    Setup setup;
    setup.scenario = sim::loadScenario(options.scenario);
    if (options.duration > 0.0)
      setup.scenario.duration = options.duration;
    if (!options.calibration_scenario.empty())
      setup.calibrated_bias = staticBias(options.calibration_scenario);
    setup.paper = tunePaper(setup.scenario, setup.calibrated_bias, options.settle);

    const std::vector<std::string> methods = methodNames(options, setup.paper.holds_station);
    Results results;
    for (int seed = 1; seed <= options.seeds; ++seed)
    {
      std::cerr << "\rseed " << seed << "/" << options.seeds << std::flush;
      runSeed(setup, options, seed, &results);
    }
    std::cerr << "\n";

    std::ofstream csv;
    if (csv_file)
      csv.open(csv_file->temporary());
    const std::string table = errorTable(methods, results.errors, &csv) + setup.paper.note +
                              periodTable(results.periods) + boundTable(results.errors, setup.scenario, options.settle);
    std::ostringstream heading;
    heading << "scenario " << setup.scenario.name << ": " << setup.scenario.rate << " Hz, " << setup.scenario.duration
            << " s; medians over seeds 1.." << options.seeds << "; RMS errors from " << options.settle
            << " s to the end\n";
    std::cout << heading.str() << table;
    if (csv_file)
    {
      csv.close();
      if (!csv)
        throw std::runtime_error("cannot write output '" + options.csv + "' (disk full?)");
      csv_file->commit();
    }
    if (markdown_file)
      markdown_file->commit(heading.str() + "\n" + table);
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "\nevaluate_compensator: " << e.what() << "\n";
    return 1;
  }
}
