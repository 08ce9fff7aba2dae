// Sim-to-real gap diagnosis: effect candidates fitted on the first part of a recording and judged
// on the withheld rest, the verdict, and the report. See docs/gap.md.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "periodic_bias_compensation/gap/features.h"
#include "periodic_bias_compensation/gap/motion.h"
#include "periodic_bias_compensation/gap/recording.h"
#include "periodic_bias_compensation/sim/scenario.h"

namespace periodic_bias_compensation::gap
{
struct DiagnoseOptions
{
  int ensemble = 8;           ///< simulated runs per model
  double fit_fraction = 0.6;  ///< the fit sees [0, fit_fraction), the gap is measured after
  int threads = 2;
  double min_shrink = 0.3;            ///< below: "no candidate explains the gap"
  double pair_gain = 0.15;            ///< a pair is reported if it shrinks this much more
  std::uint64_t seed_base = 1000003;  ///< ensemble seeds seed_base + i (never the real's)
  double truth_smooth = 0.2;          ///< moving average of the truth comparison [s]
  int truth_segments = 8;             ///< time segments of the truth comparison
  bool verbose = false;
};

/// One candidate effect with fitted parameters and its gap on the withheld part.
struct Candidate
{
  std::string effect;                                                ///< vocabulary name, or "a+b" for a pair
  std::vector<sim::EffectSpec> specs;                                ///< what is added / changed in the scenario
  nlohmann::ordered_json params = nlohmann::ordered_json::object();  ///< fitted parameters
  std::string note;                                                  ///< how it was fitted
  double gap_before = 0.0;
  double gap_after = 0.0;
  double shrink = 0.0;          ///< (before - after) / (before - typical null gap), at most 1
  std::vector<double> z_after;  ///< withheld z-scores with the effect
  OwnShrink own;                ///< on the withheld features it moves
  /// Fitted parameters that the fitter's search range stopped, each "name = value, ...": the
  /// effect may be larger than the fit says, or another one. A verdict on such a fit is never
  /// confident (confidence below 0.5).
  std::vector<std::string> at_limit;
};

/// Directly visible effect (stamps, lattice, clipping, gaps).
struct DirectDetection
{
  std::string effect;
  bool detected = false;
  std::string evidence;
};

struct Report
{
  std::string real_source;
  std::string scenario_name;
  MotionFit motion;  ///< the motion stage; sensor effects are judged against motion.fitted
  double rate = 0.0;
  double duration = 0.0;
  std::size_t samples = 0;
  FeatureLayout layout_all;  ///< layout of the whole recording ("where")
  std::vector<double> real_all;
  EnsembleStats ens_all;
  std::vector<Departure> where;
  double gap_all = 0.0;
  double null_gap = 0.0;      ///< largest gap of one ensemble member vs the rest
  FeatureLayout layout_held;  ///< layout of the withheld part
  std::vector<double> real_held;
  EnsembleStats ens_held;
  double gap_before = 0.0;  ///< withheld part, scenario as given
  double null_gap_held = 0.0;
  double null_gap_typical = 0.0;                 ///< median gap of one member vs the rest (shrink reference)
  double max_z_held = 0.0;                       ///< largest |z| of the real withheld part
  double null_max_z_held = 0.0;                  ///< largest |z| of one member vs the rest
  std::vector<std::vector<double>> null_z_held;  ///< each member's leaveOneOutZ on the withheld part
  std::vector<Candidate> ranking;                ///< best first
  std::vector<DirectDetection> direct;
  // verdict
  std::string verdict_effect;  ///< effect name, "a+b", "none" (no candidate explains) or "no_gap"
  nlohmann::ordered_json verdict_params = nlohmann::ordered_json::object();  ///< the verdict's fitted parameters
  double confidence = 0.0;
  double shrink_withheld = 0.0;
  std::string verdict_text;
  int best = -1;  ///< index of the verdict in ranking, -1 for none
  // localised places: top departures of the withheld part, before and after the verdict
  std::vector<Departure> where_held;
  std::vector<double> where_held_after;
  double seconds = 0.0;  ///< wall time
  // Curves for plots (CSV text): withheld part, real vs ensemble median vs ensemble with the verdict.
  std::string psd_csv;       ///< channel,f,real,sim,sim_effect
  std::string allan_csv;     ///< channel,tau,real,sim,sim_effect
  std::string drift_csv;     ///< channel,t,real,sim_lo,sim_med,sim_hi,sim_effect_med (block means, whole recording)
  std::string features_csv;  ///< index,channel,quantity,range,segment,real,sim,spread,z_before,z_after
  std::vector<std::vector<double>> ens_held_members;  ///< for plots
  // Truth (when the recording has one): real minus the ideal IMU of its truth, against the same
  // residual of every ensemble member (its own truth); departures also go into `where`.
  bool has_truth = false;
  std::vector<Departure> truth_where;  ///< stage "truth", quantity truth_mean / truth_std
  std::vector<Departure> stage_where;  ///< stage "compensator" (its pipeline on real vs ensemble)
  std::string truth_csv;               ///< channel,t,real,sim_lo,sim_med,sim_hi (block means of the residual)
  std::string motion_csv;  ///< f,real,given,fitted: heave spectra (motionCsv; empty when the motion does not differ)
};

/// Full diagnosis of a real recording against a scenario.
Report diagnose(const Recording& real, const sim::Scenario& scenario, const DiagnoseOptions& options);

/// A further step of a forward selection (diagnose_gap's stepwise diagnosis): the candidates and
/// the verdict of `scenario` (the first diagnosis's fitted motion with effects added) against the
/// same recording, the motion taken as `first` fitted it: not fitted again, its features left out
/// where `first` left them out. Only what a step needs is made: the report's motion, gaps,
/// ranking, best, verdict and confidence; no compensator, truth or `where` stage, no plot curves.
/// @throws std::invalid_argument when `first` is not a diagnosis of this recording
Report diagnoseStep(const Recording& real, const sim::Scenario& scenario, const Report& first,
                    const DiagnoseOptions& options);

/// The scenario with a candidate's effects in place of those of the same name.
sim::Scenario applyCandidate(const sim::Scenario& scenario, const Candidate& candidate);

/// v to 6 significant digits, the precision of the numbers in report.json; non-finite values pass
/// through (nlohmann::json writes them as null).
double sixDigits(double v);

/// report.json: its keys in the order written.
nlohmann::ordered_json reportJson(const Report& report);

/// One-screen summary.
std::string reportSummary(const Report& report);

/// Fitted effect candidates for a real recording against a base ensemble (fit part only).
/// Exposed for tests.
std::vector<Candidate> fitCandidates(const Recording& real_fit, const std::vector<Recording>& sims_fit,
                                     const sim::Scenario& scenario);

/// Runs fn(i) for i in [0, n) on `threads` threads.
void parallelFor(int n, int threads, const std::function<void(int)>& fn);
}  // namespace periodic_bias_compensation::gap
