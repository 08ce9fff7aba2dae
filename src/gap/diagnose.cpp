// The diagnosis: ensemble of the scenario as given, "where" departures, effect candidates
// fitted on the first part, re-simulated and judged on the withheld part, verdict, reports.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <future>
#include <set>
#include <sstream>
#include <stdexcept>

#include "periodic_bias_compensation/gap/diagnose.h"
#include "periodic_bias_compensation/gap/signal.h"
#include "periodic_bias_compensation/gap/truth.h"
#include "periodic_bias_compensation/sim/effects.h"

namespace periodic_bias_compensation::gap
{
namespace
{
sim::Scenario withCandidate(const sim::Scenario& base, const std::vector<sim::EffectSpec>& specs)
{
  sim::Scenario s = base;
  std::set<std::string> names;
  for (const auto& e : specs)
  {
    names.insert(e.name);
  }
  s.effects.erase(std::remove_if(s.effects.begin(), s.effects.end(),
                                 [&names](const sim::EffectSpec& e) { return names.count(e.name) > 0; }),
                  s.effects.end());
  for (const auto& e : specs)
  {
    s.effects.push_back(e);
  }
  return s;
}

std::string num(double v)
{
  if (!std::isfinite(v))
  {
    return "null";
  }
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

nlohmann::ordered_json departureJson(const Departure& d)
{
  return { { "axis", d.where.channel },
           { "quantity", d.where.quantity },
           { "range", d.where.range },
           { "segment", d.where.segment },
           { "stage", d.where.stage },
           { "real", sixDigits(d.real) },
           { "sim_median", sixDigits(d.sim_median) },
           { "size_z", sixDigits(d.z) } };
}

/// Means of `blocks` consecutive blocks of rows (the last block takes what is left).
Eigen::MatrixXd blockMeans(const Eigen::MatrixXd& x, int blocks)
{
  Eigen::MatrixXd out(blocks, x.cols());
  const Eigen::Index n = x.rows();
  const Eigen::Index bl = std::max<Eigen::Index>(1, n / blocks);
  for (int b = 0; b < blocks; ++b)
  {
    const Eigen::Index a = std::min(n - 1, b * bl);
    const Eigen::Index len = std::max<Eigen::Index>(1, std::min(bl, n - a));
    out.row(b) = x.middleRows(a, len).colwise().mean();
  }
  return out;
}

/// Block-mean curves of several runs against the real one: channel,t,real,sim_lo,sim_med,sim_hi[,extra].
std::string blockCsv(const Eigen::MatrixXd& real, const std::vector<Eigen::MatrixXd>& runs, double duration,
                     const std::vector<Eigen::MatrixXd>* extra = nullptr)
{
  std::ostringstream o;
  const int blocks = static_cast<int>(real.rows());
  for (int ch = 0; ch < kChannels; ++ch)
  {
    for (int b = 0; b < blocks; ++b)
    {
      std::vector<double> v, e;
      for (const auto& r : runs)
      {
        v.push_back(r(b, ch));
      }
      for (std::size_t i = 0; extra != nullptr && i < extra->size(); ++i)
      {
        e.push_back((*extra)[i](b, ch));
      }
      std::sort(v.begin(), v.end());
      std::sort(e.begin(), e.end());
      o << channelNames()[ch] << "," << num((b + 0.5) * duration / blocks) << "," << num(real(b, ch)) << ","
        << num(v.front()) << "," << num(v[v.size() / 2]) << "," << num(v.back());
      if (extra != nullptr)
      {
        o << "," << num(e.empty() ? 0.0 : e[e.size() / 2]);
      }
      o << "\n";
    }
  }
  return o.str();
}

/// Curves of one run for the plots: PSD and Allan deviation of the withheld part, block means of
/// the whole run (drift).
struct Curves
{
  std::vector<Psd> psd;
  std::vector<std::vector<double>> adev;
  Eigen::MatrixXd blocks;
};

Curves curvesOf(const Recording& whole, double fit_fraction, double rate, int nseg, const std::vector<int>& ms)
{
  Curves c;
  const Recording held = sliceFraction(whole, fit_fraction, 1.0);
  for (int ch = 0; ch < kChannels; ++ch)
  {
    c.psd.push_back(welch(held.data.col(ch), rate, nseg));
    c.adev.push_back(allanDeviation(held.data.col(ch), ms));
  }
  c.blocks = blockMeans(whole.data, 64);
  return c;
}

/// Equivalence classes of effects whose outputs are the same signal (a line is a line).
bool equivalent(const std::string& a, const std::string& b)
{
  auto line = [](const std::string& e) { return e == "periodic_bias" || e == "vibration"; };
  return a == b || (line(a) && line(b));
}

/// What the stages of a diagnosis share, fixed before the first run is simulated (but for the
/// scenario, which the motion stage may replace).
struct DiagnoseContext
{
  const DiagnoseOptions& opt;
  Recording real;
  sim::Scenario scenario;    ///< matched to the recording
  int runs = 0;              ///< ensemble size
  bool truth = false;        ///< the recording has a truth
  bool orientation = false;  ///< the recording has a reported orientation
  bool temperature = false;  ///< the recording and the scenario have a temperature
  int nseg = 0;              ///< Welch segment of the withheld part
  std::vector<int> allan_m;  ///< Allan taus of the withheld part [samples]

  DiagnoseContext(const DiagnoseOptions& options, const Recording& recording) : opt(options), real(recording)
  {
  }

  std::uint64_t seed(int i) const
  {
    return opt.seed_base + static_cast<std::uint64_t>(i);
  }
};

/// Blocks of the truth residual's drift curves.
constexpr int kTruthBlocks = 64;

/// The base ensemble: whole runs of the scenario, their plot curves (withheld part) and, with a
/// truth, each run's truth features and residual block means.
struct BaseEnsemble
{
  std::vector<Recording> runs;
  std::vector<Curves> curves;
  std::vector<std::vector<double>> truth_members;
  std::vector<Eigen::MatrixXd> truth_runs;
};

/// Checks the recording, matches the scenario to it and fills the report's header and the
/// recording's features of the withheld part.
DiagnoseContext prepare(const Recording& real_in, const sim::Scenario& scenario_in, const DiagnoseOptions& opt,
                        Report* rep)
{
  DiagnoseContext context(opt, real_in);
  Recording& real = context.real;
  if (real.rate <= 0.0)
  {
    real.rate = estimateRate(real);
  }
  if (real.size() < 200 || real.rate <= 0.0)
  {
    throw std::runtime_error("recording too short for a diagnosis (" + std::to_string(real.size()) + " samples)");
  }
  context.scenario = matchScenario(scenario_in, real);
  sim::validateScenario(context.scenario);
  rep->real_source = real.source;
  rep->scenario_name = context.scenario.name;
  rep->rate = real.rate;
  rep->duration = real.stamp.back() - real.stamp.front();
  rep->samples = real.size();
  context.runs = std::max(3, opt.ensemble);
  context.truth = real.truth.size() >= 3;
  const Recording real_held = sliceFraction(real, opt.fit_fraction, 1.0);
  const std::size_t n_held = real_held.size();
  context.nseg = welchSegment(n_held);
  for (int m = 1; static_cast<std::size_t>(m) * 10 <= n_held; m *= 2)
  {
    context.allan_m.push_back(m);
  }
  context.orientation = real.has_orientation;
  context.temperature = real.has_temperature && context.scenario.temperature.enabled;
  rep->layout_held = makeLayout(real.rate, n_held, context.orientation, context.temperature);
  rep->real_held = computeFeatures(real_held, rep->layout_held);
  return context;
}

/// Simulates the base ensemble of the context's scenario. With a truth in the recording, each
/// run's residual against its own truth (then dropped: it is large) is reduced to the truth
/// features at once; the plot curves of the runs are taken on the way. `simulated`, when given
/// and the recording has no truth: the runs of the context's scenario with its seeds, already
/// simulated (they are taken instead of simulated again). `runs_only` (a stepwise step): the runs
/// alone, without their plot curves and truth features.
void simulateBase(const DiagnoseContext& context, BaseEnsemble* base, std::vector<Recording>* simulated = nullptr,
                  bool runs_only = false)
{
  const int runs = context.runs;
  const DiagnoseOptions& opt = context.opt;
  const bool truth = context.truth && !runs_only;
  const bool reuse = simulated && !truth && static_cast<int>(simulated->size()) == runs;
  base->runs = reuse ? std::move(*simulated) : std::vector<Recording>(runs);
  base->curves.resize(runs_only ? 0 : runs);
  base->truth_members.resize(truth ? runs : 0);
  base->truth_runs.resize(truth ? runs : 0);
  parallelFor(runs, opt.threads, [&](int i) {
    Recording& run = base->runs[i];
    if (!reuse)
      run = simulateRecording(context.scenario, context.seed(i), truth);
    run.rate = context.real.rate;
    if (!runs_only)
      base->curves[i] = curvesOf(run, opt.fit_fraction, context.real.rate, context.nseg, context.allan_m);
    if (truth)
    {
      const Eigen::MatrixXd res = truthResidual(run, context.scenario.gravity, opt.truth_smooth);
      base->truth_members[i] = truthFeatures(res, opt.truth_segments);
      base->truth_runs[i] = blockMeans(res, kTruthBlocks);
      run.truth = TruthTrack();
    }
  });
}

/// Features of the withheld parts of some runs.
std::vector<std::vector<double>> heldMembers(const DiagnoseContext& context, const Report& rep,
                                             const std::vector<Recording>& runs)
{
  std::vector<std::vector<double>> members(runs.size());
  parallelFor(static_cast<int>(runs.size()), context.opt.threads, [&](int i) {
    members[i] = computeFeatures(sliceFraction(runs[i], context.opt.fit_fraction, 1.0), rep.layout_held);
  });
  return members;
}

/// The null z-scores of an ensemble: each member against the rest.
std::vector<std::vector<double>> nullZ(const std::vector<std::vector<double>>& members, const FeatureLayout& layout)
{
  std::vector<std::vector<double>> z;
  for (int i = 0; i < static_cast<int>(members.size()); ++i)
  {
    z.push_back(leaveOneOutZ(members, i, layout));
  }
  return z;
}

/// The median of the gaps of some z-score vectors (0 when there are none): of nullZ, the typical
/// null gap.
double medianGap(const std::vector<std::vector<double>>& zs)
{
  std::vector<double> gaps;
  for (const std::vector<double>& z : zs)
  {
    gaps.push_back(gapOf(z));
  }
  std::sort(gaps.begin(), gaps.end());
  return gaps.empty() ? 0.0 : gaps[gaps.size() / 2];
}

/// Directional spreadings [rad] and response coherences the motion stage tries on a sea whose
/// responses it fitted.
const std::vector<double> kSpreadingTrials = { 0.4, 0.8 };
const std::vector<double> kCoherenceTrials = { 0.5, 0.0 };

/// The fitted motion leaves the withheld part unexplained when its gap exceeds the typical null
/// gap this many times [-]: a motion the scenario's sea cannot take (a recorded one's spectrum, a
/// buoy's rotations), not one a sensor effect is to be credited with.
constexpr double kMotionUnexplained = 4.0;

/// Runs of a motion candidate's ensemble on which it is screened [-] (on the ensemble's first
/// seeds; the adopted candidate is simulated on the rest): half of the default ensemble, the
/// motion's shape moving the features by many spreads where it differs.
constexpr int kMotionScreenRuns = 4;

/// Whether a feature carries the shape of the motion, which a motion of another kind can leave
/// unfitted: spectra, Allan deviations, spreads, the axes' correlations and, on a moving scenario,
/// the means (the specific force's mean along the body falls with the tilt's variance,
/// g (1 - E[theta^2] / 2); a part's mean heading with the heading's wander). At rest the tilt and
/// heading are fitted as they are, and the means stay judged; an orientation's leak and the stamps
/// always do.
bool motionShape(const FeatureInfo& f, bool moving)
{
  return f.quantity == "psd" || f.quantity == "allan" || f.quantity == "log_std" || f.quantity == "corr" ||
         (moving && (f.quantity == "mean" || f.quantity == "yaw_mean"));
}

/// With the motion left unexplained (kMotionUnexplained), leaves out of the sensor diagnosis every
/// withheld feature of its shape (motionShape; `moving`: the scenario is not at rest) that a
/// motion candidate moves (reach: by more than kMovedSpreads of the given ensemble's spreads) and
/// that still departs from the fitted ensemble (`members`; the recording's z-scores against it:
/// `z`) by more than kZThreshold: the motion reaches it and could not fit it. Marks them in the
/// report's layout.
void leaveOutMotion(const std::vector<std::vector<double>>& members, const std::vector<double>& z,
                    const std::vector<double>& reach, bool moving, Report* rep)
{
  const double null_gap = medianGap(nullZ(members, rep->layout_held));
  rep->motion.unexplained = rep->motion.gap_after > kMotionUnexplained * null_gap;
  if (!rep->motion.unexplained)
  {
    return;
  }
  for (std::size_t k = 0; k < z.size(); ++k)
  {
    FeatureInfo& f = rep->layout_held.info[k];
    if (motionShape(f, moving) && reach[k] > kMovedSpreads && std::abs(z[k]) > kZThreshold)
    {
      f.left_out = true;
      rep->motion.left_out.push_back(f.channel + " " + f.quantity + (f.range.empty() ? "" : " " + f.range) + " " +
                                     f.segment);
    }
  }
}

/// 0. Motion: a tilt, heading or sea state of its own is fitted before any sensor effect, then the
/// sea's responses and spreading; the fit that brings the withheld part closest becomes the
/// scenario of the base ensemble.
void motionStage(DiagnoseContext* context, BaseEnsemble* base, Report* rep)
{
  // The motion summaries of an ensemble's runs, in threads.
  const auto summaries = [&](const std::vector<Recording>& runs) {
    std::vector<MotionSummary> out(runs.size());
    parallelFor(static_cast<int>(runs.size()), context->opt.threads, [&](int i) { out[i] = summariseMotion(runs[i]); });
    return out;
  };
  const MotionSummary real = summariseMotion(context->real);
  // The adopted ensemble's summaries; none while they are to be made from best_runs.
  std::optional<std::vector<MotionSummary>> best_summaries = summaries(base->runs);
  rep->motion = fitMotion(real, context->scenario, *best_summaries);
  if (!rep->motion.differs)
  {
    // With the tilt, heading and sea state as the scenario's, only a rotation's response says the
    // motion differs: surge and sway differences are left to the accelerometer's effects.
    std::vector<std::string> unused;
    if (!fitWaveResponses(real, context->scenario, *best_summaries, &unused, true))
    {
      return;
    }
    rep->motion.differs = true;
  }
  const std::vector<std::vector<double>> given_members = heldMembers(*context, *rep, base->runs);
  rep->motion.gap_before = gapOf(zScores(rep->real_held, ensembleStats(given_members, rep->layout_held)));
  // The candidates are screened on the first `screen` seeds of the ensemble (the base's runs on
  // the same seeds are the reference); the adopted one is completed to the whole ensemble.
  const int screen = std::min(context->runs, kMotionScreenRuns);
  const std::vector<std::vector<double>> given_screen(given_members.begin(), given_members.begin() + screen);
  const EnsembleStats given = ensembleStats(given_screen, rep->layout_held);
  double best = gapOf(zScores(rep->real_held, given));
  std::vector<Recording> best_runs;  // the adopted fit's runs (empty: the base's)
  std::vector<std::vector<double>> best_members = given_screen;
  // How far any motion candidate moves each feature, in spreads of the given ensemble.
  std::vector<double> reach(given.median.size(), 0.0);
  // Each candidate's ensemble, and its withheld gap; the closest is adopted.
  const auto consider = [&](const MotionCandidate& candidate) {
    std::vector<Recording> runs(screen);
    parallelFor(screen, context->opt.threads,
                [&](int i) { runs[i] = simulateRecording(candidate.scenario, context->seed(i)); });
    std::vector<std::vector<double>> members = heldMembers(*context, *rep, runs);
    const EnsembleStats stats = ensembleStats(members, rep->layout_held);
    for (std::size_t k = 0; k < reach.size(); ++k)
    {
      reach[k] = std::max(reach[k], std::abs(stats.median[k] - given.median[k]) / given.spread[k]);
    }
    const double gap = gapOf(zScores(rep->real_held, stats));
    if (gap < best)
    {
      best = gap;
      rep->motion.adopted = candidate.what;
      rep->motion.fitted = candidate.scenario;
      best_runs = std::move(runs);
      best_members = std::move(members);
      best_summaries.reset();  // summarised when needed
    }
  };
  const auto adopted_summaries = [&]() -> const std::vector<MotionSummary>& {
    if (!best_summaries)
      best_summaries = summaries(best_runs);
    return *best_summaries;
  };
  for (const MotionCandidate& candidate : rep->motion.candidates)
  {
    consider(candidate);
  }
  // Then the sea's shape: its responses per degree of freedom against the ensemble of that fit,
  // its directional spreading and its response coherence (both decorrelate surge, sway, roll,
  // pitch and yaw), and the responses once more.
  const auto current = [&]() { return rep->motion.adopted.empty() ? context->scenario : rep->motion.fitted; };
  const auto label = [&](const std::string& what) {
    return rep->motion.adopted.empty() ? what : rep->motion.adopted + ", " + what;
  };
  const auto responses = [&]() {
    std::optional<MotionCandidate> fit = fitWaveResponses(real, current(), adopted_summaries(), &rep->motion.findings);
    if (fit)
    {
      fit->what = label(fit->what);
      rep->motion.candidates.push_back(*fit);
      consider(*fit);
    }
    return fit.has_value();
  };
  const auto trials = [&](const std::string& what, const std::vector<double>& values,
                          const std::function<void(double, sim::Sea*)>& set) {
    const sim::Scenario from = current();
    const std::string from_label = label(what);
    for (double value : values)
    {
      MotionCandidate candidate{ from_label + " " + num(value), from };
      set(value, &candidate.scenario.motion.sea);
      rep->motion.candidates.push_back(candidate);
      consider(candidate);
    }
  };
  if (responses())
  {
    trials("spreading [rad]", kSpreadingTrials, [](double v, sim::Sea* sea) {
      for (sim::WaveSystem& system : sea->systems)
      {
        system.spreading = v;
      }
    });
    trials("response coherence", kCoherenceTrials, [](double v, sim::Sea* sea) { sea->response_coherence = v; });
    responses();
  }
  // Last, the short waves the hull does not follow (its length), against the fit so far.
  std::optional<MotionCandidate> short_waves =
      fitShortWaves(real, current(), adopted_summaries(), &rep->motion.findings);
  if (short_waves)
  {
    short_waves->what = label(short_waves->what);
    rep->motion.candidates.push_back(*short_waves);
    consider(*short_waves);
  }
  if (rep->motion.adopted.empty())
  {
    best_members = given_members;
  }
  else
  {
    best_runs.resize(context->runs);
    parallelFor(context->runs - screen, context->opt.threads, [&](int i) {
      best_runs[screen + i] = simulateRecording(rep->motion.fitted, context->seed(screen + i));
    });
    const std::vector<Recording> rest(best_runs.begin() + screen, best_runs.end());
    for (std::vector<double>& member : heldMembers(*context, *rep, rest))
    {
      best_members.push_back(std::move(member));
    }
    best_summaries.reset();
  }
  rep->motion_csv = motionCsv(rep->motion, adopted_summaries());
  const std::vector<double> z_after = zScores(rep->real_held, ensembleStats(best_members, rep->layout_held));
  rep->motion.gap_after = gapOf(z_after);
  leaveOutMotion(best_members, z_after, reach, context->scenario.motion.type != sim::MotionType::kStatic, rep);
  if (!rep->motion.adopted.empty())
  {
    context->scenario = rep->motion.fitted;
    simulateBase(*context, base, &best_runs);
  }
}

/// The compensator's pipeline stages of the real recording, which depend on nothing simulated: with
/// more than one thread they are worked out beside the stages before theirs.
std::future<std::vector<double>> realStages(const DiagnoseContext& context)
{
  return std::async(context.opt.threads > 1 ? std::launch::async : std::launch::deferred,
                    [&context]() { return stageFeatures(context.real, 4); });
}

/// The compensator's pipeline stages on the real recording (realStages) against the same on every
/// run, the runs in threads (the core and the spectra plan FFTW under one lock, fftw_planner.h).
void compensatorStage(const DiagnoseContext& context, const BaseEnsemble& base,
                      std::future<std::vector<double>>* real_stages, Report* rep)
{
  std::vector<std::vector<double>> stage_members(context.runs);
  parallelFor(context.runs, context.opt.threads, [&](int i) { stage_members[i] = stageFeatures(base.runs[i], 4); });
  const FeatureLayout layout = stageLayout(rep->duration, 4);
  rep->stage_where = rankDepartures(real_stages->get(), ensembleStats(stage_members, layout), layout);
}

/// The recording minus the ideal IMU of its truth, against the same residual of every run.
void truthStage(const DiagnoseContext& context, const BaseEnsemble& base, Report* rep)
{
  const DiagnoseOptions& opt = context.opt;
  rep->has_truth = true;
  const Eigen::MatrixXd res = truthResidual(context.real, context.scenario.gravity, opt.truth_smooth);
  const FeatureLayout layout = truthLayout(rep->duration, opt.truth_segments);
  rep->truth_where =
      rankDepartures(truthFeatures(res, opt.truth_segments), ensembleStats(base.truth_members, layout), layout);
  rep->truth_csv = "channel,t,real,sim_lo,sim_med,sim_hi\n" +
                   blockCsv(blockMeans(res, kTruthBlocks), base.truth_runs, rep->duration);
}

/// 1. Where: departures on the whole recording, with the truth and compensator stages, ranked by
/// |z|; the gap and the null gap of the whole recording.
void whereStage(const DiagnoseContext& context, const BaseEnsemble& base, Report* rep)
{
  rep->layout_all = makeLayout(context.real.rate, context.real.size(), context.orientation, context.temperature);
  rep->real_all = computeFeatures(context.real, rep->layout_all);
  std::vector<std::vector<double>> all(context.runs);
  parallelFor(context.runs, context.opt.threads,
              [&](int i) { all[i] = computeFeatures(base.runs[i], rep->layout_all); });
  rep->ens_all = ensembleStats(all, rep->layout_all);
  rep->where = rankDepartures(rep->real_all, rep->ens_all, rep->layout_all);
  rep->where.insert(rep->where.end(), rep->truth_where.begin(), rep->truth_where.end());
  rep->where.insert(rep->where.end(), rep->stage_where.begin(), rep->stage_where.end());
  std::stable_sort(rep->where.begin(), rep->where.end(),
                   [](const Departure& a, const Departure& b) { return std::abs(a.z) > std::abs(b.z); });
  rep->gap_all = gapOf(zScores(rep->real_all, rep->ens_all));
  for (int i = 0; i < context.runs; ++i)
  {
    rep->null_gap = std::max(rep->null_gap, gapOf(leaveOneOutZ(all, i, rep->layout_all)));
  }
}

/// 2. Withheld part: the base ensemble's features there, the gap before any candidate and the
/// null levels. Returns the runs' first parts (for the fit) and drops the whole runs.
std::vector<Recording> withheldStage(const DiagnoseContext& context, BaseEnsemble* base, Report* rep,
                                     std::vector<double>* z_before)
{
  const int runs = context.runs;
  const double fit_fraction = context.opt.fit_fraction;
  std::vector<Recording> base_fit(runs);
  rep->ens_held_members.resize(runs);
  parallelFor(runs, context.opt.threads, [&](int i) {
    base_fit[i] = sliceFraction(base->runs[i], 0.0, fit_fraction);
    rep->ens_held_members[i] = computeFeatures(sliceFraction(base->runs[i], fit_fraction, 1.0), rep->layout_held);
  });
  base->runs.clear();
  rep->ens_held = ensembleStats(rep->ens_held_members, rep->layout_held);
  *z_before = zScores(rep->real_held, rep->ens_held);
  rep->gap_before = gapOf(*z_before);
  if (!rep->motion.differs)
  {
    rep->motion.gap_before = rep->motion.gap_after = rep->gap_before;
  }
  rep->null_z_held = nullZ(rep->ens_held_members, rep->layout_held);
  for (const std::vector<double>& zn : rep->null_z_held)
  {
    rep->null_gap_held = std::max(rep->null_gap_held, gapOf(zn));
    for (double v : zn)
    {
      rep->null_max_z_held = std::max(rep->null_max_z_held, std::abs(v));
    }
  }
  rep->null_gap_typical = medianGap(rep->null_z_held);
  for (double v : *z_before)
  {
    rep->max_z_held = std::max(rep->max_z_held, std::abs(v));
  }
  return base_fit;
}

/// Direct detections (stamps, lattice, clipping, gaps) on the whole recording.
std::vector<DirectDetection> directDetections(const Recording& real)
{
  std::vector<DirectDetection> direct;
  const StampStats st = stampStats(real.stamp, real.rate);
  char buf[256];
  std::snprintf(buf, sizeof(buf), "stamp residual robust std %.3g s (rate %.6g Hz), %.0f backwards", st.jitter, st.rate,
                st.backwards);
  direct.push_back({ "timestamp_jitter", st.jitter > 0.02 / real.rate, buf });
  std::snprintf(buf, sizeof(buf), "%.3g %% of samples missing in %.0f gaps (mean %.3g samples)", 100 * st.lost_fraction,
                st.bursts, st.mean_burst);
  direct.push_back({ "dropouts", st.bursts > 0, buf });
  const double repeated = repeatedFraction(real.data);
  std::snprintf(buf, sizeof(buf), "%.3g %% of the samples repeat their predecessor in all six channels",
                100 * repeated);
  direct.push_back({ "sample_hold", repeated > 0.02, buf });
  std::string lat, clip;
  bool any_lat = false, any_clip = false;
  for (int c = 0; c < kChannels; ++c)
  {
    const double q = latticeStep(real.data.col(c));
    double lim = 0;
    const double ft = flatTopFraction(real.data.col(c), &lim);
    std::snprintf(buf, sizeof(buf), "%s%s %.4g", lat.empty() ? "" : ", ", channelNames()[c].c_str(), q);
    lat += buf;
    std::snprintf(buf, sizeof(buf), "%s%s %.3g %% at %.4g", clip.empty() ? "" : ", ", channelNames()[c].c_str(),
                  100 * ft, lim);
    clip += buf;
    any_lat = any_lat || q > 0;
    any_clip = any_clip || ft > 1e-4;
  }
  direct.push_back({ "quantization", any_lat, "lattice step per axis (0 = none): " + lat });
  direct.push_back({ "saturation", any_clip, "samples at the largest magnitude: " + clip });
  return direct;
}

/// Simulates every candidate with the ensemble's seeds and measures its gap and shrink on the
/// withheld part.
void judge(const DiagnoseContext& context, const Report& rep, std::vector<Candidate>* list)
{
  const int runs = context.runs;
  const int nc = static_cast<int>(list->size());
  std::vector<std::vector<std::vector<double>>> feats(nc, std::vector<std::vector<double>>(runs));
  std::vector<std::string> errors(nc);
  std::vector<sim::Scenario> scenarios;
  for (const Candidate& candidate : *list)
  {
    scenarios.push_back(withCandidate(context.scenario, candidate.specs));
  }
  // Per seed, every candidate on the one motion (they differ only in their effects).
  parallelFor(runs, context.opt.threads, [&](int i) {
    const std::vector<std::string> failed = simulateVariants(scenarios, context.seed(i), [&](int c, Recording& r) {
      r.rate = context.real.rate;
      feats[c][i] = computeFeatures(sliceFraction(r, context.opt.fit_fraction, 1.0), rep.layout_held);
    });
    if (i == 0)
    {
      errors = failed;  // the same on every seed: a candidate's scenario is refused when built
    }
  });
  for (int c = 0; c < nc; ++c)
  {
    Candidate& candidate = (*list)[c];
    candidate.gap_before = rep.gap_before;
    if (!errors[c].empty())
    {
      candidate.note += " (not simulated: " + errors[c] + ")";
      candidate.gap_after = rep.gap_before;
      candidate.shrink = 0.0;
      continue;
    }
    const EnsembleStats st = ensembleStats(feats[c], rep.layout_held);
    candidate.z_after = zScores(rep.real_held, st);
    candidate.gap_after = gapOf(candidate.z_after, st.spread, rep.ens_held.spread);
    const double excess = rep.gap_before - rep.null_gap_typical;
    candidate.shrink = excess > 0 ? std::min(1.0, (rep.gap_before - candidate.gap_after) / excess) : 0.0;
    candidate.own = ownShrink(rep.real_held, rep.ens_held, st, rep.null_z_held);
  }
}

/// Moves candidate i to the front, the others keeping their order.
void toFront(std::vector<Candidate>* cands, std::size_t i)
{
  std::rotate(cands->begin(), cands->begin() + static_cast<std::ptrdiff_t>(i),
              cands->begin() + static_cast<std::ptrdiff_t>(i) + 1);
}

/// A pure spectral line is the same signal for periodic_bias and vibration: when the twin
/// explains at least half as much, the line is named by its frequency (below 1 Hz a periodic
/// bias, above a vibration: the vocabulary's slow bias and engine line).
void nameLineByFrequency(std::vector<Candidate>* list)
{
  std::vector<Candidate>& cands = *list;
  if (cands.empty() || (cands[0].effect != "periodic_bias" && cands[0].effect != "vibration"))
  {
    return;
  }
  double f = -1.0;
  std::size_t twin = 0;
  for (std::size_t i = 1; i < cands.size(); ++i)
  {
    if (cands[i].effect != cands[0].effect && equivalent(cands[i].effect, cands[0].effect) &&
        cands[i].shrink >= 0.5 * cands[0].shrink)
    {
      twin = i;
    }
  }
  for (const auto& c : cands)
  {
    if (c.effect == "vibration" && !c.specs.empty())
    {
      f = c.specs.back().params.at("frequency")[0];
    }
  }
  const std::string want = f > kVibrationMinFrequency ? "vibration" : "periodic_bias";
  if (twin > 0 && f >= 0.0 && cands[twin].effect == want)
  {
    toFront(list, twin);
  }
}

/// A random walk and a Gauss-Markov bias both explain a wandering bias. The simpler random walk
/// (no correlation time) is named when it explains about as much (within 0.06), or when the
/// fitted correlation time exceeds half the recording (over that recording, a random walk) and
/// it explains nearly as much (within 0.15). A Gauss-Markov bias whose correlation time shows in
/// the recording leaves the random walk clearly behind (0.15-0.25 in validate_gap).
void preferRandomWalk(std::vector<Candidate>* list, double duration)
{
  std::vector<Candidate>& cands = *list;
  if (cands.size() < 2 || cands[0].effect != "bias_instability" || cands[0].specs.empty())
  {
    return;
  }
  const double tc = cands[0].specs.back().params.at("correlation_time")[0];
  for (std::size_t i = 1; i < cands.size(); ++i)
  {
    const double behind = cands[0].shrink - cands[i].shrink;
    if (cands[i].effect == "bias_random_walk" && (behind < 0.06 || (tc > 0.5 * duration && behind < 0.15)))
    {
      toFront(list, i);
      break;
    }
  }
}

/// The best pair of two different effects, judged; first if it explains clearly more, else last.
void tryBestPair(const DiagnoseContext& context, const Report& rep, std::vector<Candidate>* list)
{
  std::vector<Candidate>& cands = *list;
  if (cands.size() < 2 || !(cands[0].shrink > 0))
  {
    return;
  }
  std::size_t j = 1;
  while (j < cands.size() && equivalent(cands[0].effect, cands[j].effect))
  {
    ++j;
  }
  if (j >= cands.size() || !(cands[j].shrink > 0))
  {
    return;
  }
  Candidate pair;
  pair.effect = cands[0].effect + "+" + cands[j].effect;
  pair.specs = cands[0].specs;
  pair.specs.insert(pair.specs.end(), cands[j].specs.begin(), cands[j].specs.end());
  pair.params = { { cands[0].effect, cands[0].params }, { cands[j].effect, cands[j].params } };
  pair.note = "best two together";
  pair.at_limit = cands[0].at_limit;
  pair.at_limit.insert(pair.at_limit.end(), cands[j].at_limit.begin(), cands[j].at_limit.end());
  std::vector<Candidate> one{ pair };
  judge(context, rep, &one);
  if (one[0].shrink > cands[0].shrink + context.opt.pair_gain)
  {
    cands.insert(cands.begin(), one[0]);
  }
  else
  {
    cands.push_back(one[0]);
  }
}

/// 3. Candidates fitted on the first part, judged on the withheld part, ranked by shrink with the
/// naming rules applied and the best pair added.
void candidateStage(const DiagnoseContext& context, std::vector<Recording> base_fit, Report* rep)
{
  const Recording real_fit = sliceFraction(context.real, 0.0, context.opt.fit_fraction);
  std::vector<Candidate> cands = fitCandidates(real_fit, base_fit, context.scenario);
  base_fit.clear();
  judge(context, *rep, &cands);
  std::sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) { return a.shrink > b.shrink; });
  nameLineByFrequency(&cands);
  preferRandomWalk(&cands, rep->duration);
  tryBestPair(context, *rep, &cands);
  rep->ranking = cands;
}

/// An effect explains most of what it moves when its OwnShrink is at least this [-].
constexpr double kMostOfWhatItMoves = 0.8;

/// "; explaining at least 80 % of the departures each moves, though not the gap: a (S % of N
/// features), ..." for the single effects with OwnShrink >= kMostOfWhatItMoves, best first; ""
/// when none does.
std::string partlyExplained(std::vector<Candidate> ranking)
{
  ranking.erase(std::remove_if(ranking.begin(), ranking.end(),
                               [](const Candidate& c) {
                                 return c.effect.find('+') != std::string::npos || c.own.moved == 0 ||
                                        c.own.shrink < kMostOfWhatItMoves;
                               }),
                ranking.end());
  if (ranking.empty())
    return "";
  std::stable_sort(ranking.begin(), ranking.end(),
                   [](const Candidate& a, const Candidate& b) { return a.own.shrink > b.own.shrink; });
  std::string text = "; explaining at least " + num(100.0 * kMostOfWhatItMoves) +
                     " % of the departures each moves, though not the gap:";
  for (std::size_t i = 0; i < ranking.size(); ++i)
  {
    text += (i ? ", " : " ") + ranking[i].effect + " (" + num(std::round(100.0 * ranking[i].own.shrink)) + " % of " +
            std::to_string(ranking[i].own.moved) + " features)";
  }
  return text;
}

/// The highest confidence of a verdict whose fit a search limit stopped (not confident).
constexpr double kAtLimitConfidence = 0.45;

/// Verdict: no_gap, none or the best candidate with its confidence.
void verdictStage(const DiagnoseOptions& opt, Report* rep)
{
  const double significant_gap = std::max(1.5 * rep->null_gap_held, 0.05);
  const bool significant =
      rep->gap_before > significant_gap || rep->max_z_held > std::max(1.5 * rep->null_max_z_held, 2.0 * kZThreshold);
  if (!significant)
  {
    rep->verdict_effect = "no_gap";
    rep->verdict_params = nlohmann::ordered_json::object();
    rep->confidence = 0.0;
    rep->verdict_text = "no significant gap: the recording lies within the simulated ensemble's spread";
  }
  else if (rep->ranking.empty() || rep->ranking[0].shrink < opt.min_shrink)
  {
    rep->verdict_effect = "none";
    rep->verdict_params = nlohmann::ordered_json::object();
    rep->confidence = 0.0;
    rep->shrink_withheld = rep->ranking.empty() ? 0.0 : rep->ranking[0].shrink;
    rep->verdict_text = "no candidate explains the gap (best shrink below " + num(opt.min_shrink) +
                        "); the residual is reported in 'where'";
    rep->verdict_text += partlyExplained(rep->ranking);
  }
  else
  {
    const Candidate& b = rep->ranking[0];
    double second = 0.0;
    for (std::size_t i = 1; i < rep->ranking.size(); ++i)
    {
      const std::string& e = rep->ranking[i].effect;
      if (!equivalent(e, b.effect) && b.effect.find(e) == std::string::npos && e.find('+') == std::string::npos)
      {
        second = std::max(second, rep->ranking[i].shrink);
      }
    }
    rep->best = 0;
    rep->verdict_effect = b.effect;
    rep->verdict_params = b.params;
    rep->shrink_withheld = b.shrink;
    const double margin = b.shrink - std::max(0.0, second);
    rep->confidence = std::max(0.0, std::min(1.0, b.shrink)) * std::max(0.0, std::min(1.0, 0.4 + margin / 0.4));
    rep->verdict_text = b.effect + " explains " + num(100.0 * b.shrink) + " % of the gap on the withheld part";
    if (!b.at_limit.empty())
    {
      rep->confidence = std::min(rep->confidence, kAtLimitConfidence);
      rep->verdict_text += "; fitted at a search limit (" + b.at_limit.front() +
                           (b.at_limit.size() > 1 ? ", and " + std::to_string(b.at_limit.size() - 1) + " more" : "") +
                           "): the effect may be larger or another";
    }
  }
}

/// Localised places of the withheld part, before and after the verdict.
void localise(Report* rep)
{
  rep->where_held = rankDepartures(rep->real_held, rep->ens_held, rep->layout_held, kZThreshold, 12);
  if (rep->best < 0)
  {
    return;
  }
  const Candidate* best = &rep->ranking[rep->best];
  for (const Departure& d : rep->where_held)
  {
    for (std::size_t i = 0; i < rep->layout_held.info.size(); ++i)
    {
      const FeatureInfo& f = rep->layout_held.info[i];
      if (f.channel == d.where.channel && f.quantity == d.where.quantity && f.range == d.where.range &&
          f.segment == d.where.segment)
      {
        rep->where_held_after.push_back(best->z_after.empty() ? 0.0 : best->z_after[i]);
        break;
      }
    }
  }
}

/// Every feature of the withheld part: real, ensemble, z before and after the verdict.
std::string featuresCsv(const Report& rep, const std::vector<double>& z_before)
{
  std::ostringstream fs;
  fs << "index,channel,quantity,range,segment,lo,hi,real,sim,spread,z_before,z_after,left_out\n";
  for (std::size_t i = 0; i < rep.layout_held.info.size(); ++i)
  {
    const FeatureInfo& f = rep.layout_held.info[i];
    fs << i << "," << f.channel << "," << f.quantity << ",\"" << f.range << "\"," << f.segment << "," << num(f.lo)
       << "," << num(f.hi) << "," << num(rep.real_held[i]) << "," << num(rep.ens_held.median[i]) << ","
       << num(rep.ens_held.spread[i]) << "," << num(z_before[i]) << ","
       << num(rep.best >= 0 && !rep.ranking[rep.best].z_after.empty() ? rep.ranking[rep.best].z_after[i] : z_before[i])
       << "," << (f.left_out ? 1 : 0) << "\n";
  }
  return fs.str();
}

/// Curves for the plots: PSD and Allan of the withheld part (real, ensemble median, ensemble with
/// the verdict), block means of the whole recording (drift), and the features.
void plotCurves(const DiagnoseContext& context, const std::vector<Curves>& base_curves,
                const std::vector<double>& z_before, Report* rep)
{
  const int runs = context.runs;
  const double rate = context.real.rate;
  const double fit_fraction = context.opt.fit_fraction;
  const std::vector<int>& ms = context.allan_m;
  std::vector<sim::EffectSpec> specs;
  if (rep->best >= 0)
  {
    specs = rep->ranking[rep->best].specs;
  }
  const sim::Scenario eff = withCandidate(context.scenario, specs);
  const Curves cr = curvesOf(context.real, fit_fraction, rate, context.nseg, ms);
  std::vector<Curves> ce(runs);
  parallelFor(runs, context.opt.threads, [&](int i) {
    Recording r = simulateRecording(eff, context.seed(i));
    r.rate = rate;
    ce[i] = curvesOf(r, fit_fraction, rate, context.nseg, ms);
  });
  auto med = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  std::ostringstream ps, as;
  ps << "channel,f,real,sim,sim_effect\n";
  as << "channel,tau,real,sim,sim_effect\n";
  for (int ch = 0; ch < kChannels; ++ch)
  {
    const std::string& name = channelNames()[ch];
    for (std::size_t k = 1; k < cr.psd[ch].power.size(); ++k)
    {
      std::vector<double> vb, ve;
      for (int i = 0; i < runs; ++i)
      {
        vb.push_back(base_curves[i].psd[ch].power[k]);
        ve.push_back(ce[i].psd[ch].power[k]);
      }
      ps << name << "," << num(k * cr.psd[ch].df) << "," << num(cr.psd[ch].power[k]) << "," << num(med(vb)) << ","
         << num(med(ve)) << "\n";
    }
    for (std::size_t k = 0; k < ms.size(); ++k)
    {
      std::vector<double> vb, ve;
      for (int i = 0; i < runs; ++i)
      {
        vb.push_back(base_curves[i].adev[ch][k]);
        ve.push_back(ce[i].adev[ch][k]);
      }
      as << name << "," << num(ms[k] / rate) << "," << num(cr.adev[ch][k]) << "," << num(med(vb)) << "," << num(med(ve))
         << "\n";
    }
  }
  rep->psd_csv = ps.str();
  rep->allan_csv = as.str();
  std::vector<Eigen::MatrixXd> bb, be;
  for (int i = 0; i < runs; ++i)
  {
    bb.push_back(base_curves[i].blocks);
    be.push_back(ce[i].blocks);
  }
  rep->drift_csv =
      "channel,t,real,sim_lo,sim_med,sim_hi,sim_effect_med\n" + blockCsv(cr.blocks, bb, rep->duration, &be);
  rep->features_csv = featuresCsv(*rep, z_before);
}
}  // namespace

sim::Scenario applyCandidate(const sim::Scenario& scenario, const Candidate& candidate)
{
  return withCandidate(scenario, candidate.specs);
}

Report diagnose(const Recording& real_in, const sim::Scenario& scenario_in, const DiagnoseOptions& opt)
{
  const auto wall0 = std::chrono::steady_clock::now();
  Report rep;
  DiagnoseContext context = prepare(real_in, scenario_in, opt, &rep);
  std::future<std::vector<double>> real_stages = realStages(context);
  BaseEnsemble base;
  simulateBase(context, &base);
  motionStage(&context, &base, &rep);
  compensatorStage(context, base, &real_stages, &rep);
  if (context.truth)
  {
    truthStage(context, base, &rep);
  }
  whereStage(context, base, &rep);
  std::vector<double> z_before;
  std::vector<Recording> base_fit = withheldStage(context, &base, &rep, &z_before);
  rep.direct = directDetections(context.real);
  candidateStage(context, std::move(base_fit), &rep);
  verdictStage(opt, &rep);
  localise(&rep);
  plotCurves(context, base.curves, z_before, &rep);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return rep;
}

Report diagnoseStep(const Recording& real_in, const sim::Scenario& scenario_in, const Report& first,
                    const DiagnoseOptions& opt)
{
  const auto wall0 = std::chrono::steady_clock::now();
  Report rep;
  DiagnoseContext context = prepare(real_in, scenario_in, opt, &rep);
  if (rep.layout_held.info.size() != first.layout_held.info.size() || rep.samples != first.samples)
  {
    throw std::invalid_argument("diagnoseStep: the first diagnosis is of another recording");
  }
  rep.layout_held = first.layout_held;  // the same recording's, with the features left out
  rep.motion = first.motion;
  rep.motion_csv = first.motion_csv;
  BaseEnsemble base;
  simulateBase(context, &base, nullptr, true);
  std::vector<double> z_before;
  std::vector<Recording> base_fit = withheldStage(context, &base, &rep, &z_before);
  rep.direct = first.direct;
  candidateStage(context, std::move(base_fit), &rep);
  verdictStage(opt, &rep);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return rep;
}

double sixDigits(double v)
{
  return std::isfinite(v) ? std::strtod(num(v).c_str(), nullptr) : v;
}

namespace
{
nlohmann::ordered_json motionSummaryJson(const MotionSummary& m)
{
  return { { "roll", sixDigits(m.roll) },
           { "pitch", sixDigits(m.pitch) },
           { "heading", sixDigits(m.heading) },
           { "wave_height", sixDigits(m.wave_height) },
           { "peak_period", sixDigits(m.peak_period) } };
}

nlohmann::ordered_json motionJson(const MotionFit& m)
{
  return { { "differs", m.differs },
           { "adopted", m.adopted },
           { "real", motionSummaryJson(m.real) },
           { "scenario", motionSummaryJson(m.scenario) },
           { "findings", m.findings },
           { "gap_before", sixDigits(m.gap_before) },
           { "gap_after", sixDigits(m.gap_after) },
           { "unexplained", m.unexplained },
           { "left_out", m.left_out } };
}

nlohmann::ordered_json departuresJson(const std::vector<Departure>& departures)
{
  nlohmann::ordered_json j = nlohmann::ordered_json::array();
  for (const Departure& d : departures)
  {
    j.push_back(departureJson(d));
  }
  return j;
}

nlohmann::ordered_json rankingJson(const std::vector<Candidate>& ranking)
{
  nlohmann::ordered_json j = nlohmann::ordered_json::array();
  for (const Candidate& c : ranking)
  {
    j.push_back({ { "effect", c.effect },
                  { "params", c.params },
                  { "gap_before", sixDigits(c.gap_before) },
                  { "gap_after", sixDigits(c.gap_after) },
                  { "shrink", sixDigits(c.shrink) },
                  { "own",
                    { { "moved", c.own.moved },
                      { "gap_before", sixDigits(c.own.before) },
                      { "gap_after", sixDigits(c.own.after) },
                      { "null", sixDigits(c.own.null_level) },
                      { "shrink", sixDigits(c.own.shrink) } } },
                  { "fit", c.note },
                  { "at_limit", c.at_limit } });
  }
  return j;
}
}  // namespace

nlohmann::ordered_json reportJson(const Report& r)
{
  nlohmann::ordered_json j;
  j["schema"] = "periodic_bias_compensation/gap_report/1";
  j["real"] = { { "source", r.real_source },
                { "rate_hz", sixDigits(r.rate) },
                { "duration_s", sixDigits(r.duration) },
                { "samples", r.samples } };
  j["scenario"] = r.scenario_name;
  j["motion"] = motionJson(r.motion);
  j["gap_metric"] = "rms over features of log(1 + max(0, |z| - 3)), z = (real - ensemble median) / ensemble spread";
  j["gap_all"] = sixDigits(r.gap_all);
  j["null_gap_all"] = sixDigits(r.null_gap);
  j["where"] = departuresJson(r.where);
  j["direct"] = nlohmann::ordered_json::array();
  for (const DirectDetection& d : r.direct)
  {
    j["direct"].push_back({ { "effect", d.effect }, { "detected", d.detected }, { "evidence", d.evidence } });
  }
  j["withheld"] = { { "gap_before", sixDigits(r.gap_before) },
                    { "null_gap", sixDigits(r.null_gap_held) },
                    { "null_gap_typical", sixDigits(r.null_gap_typical) },
                    { "max_z", sixDigits(r.max_z_held) },
                    { "null_max_z", sixDigits(r.null_max_z_held) } };
  j["ranking"] = rankingJson(r.ranking);
  j["verdict"] = { { "effect", r.verdict_effect },
                   { "params", r.verdict_params },
                   { "confidence", sixDigits(r.confidence) },
                   { "shrink_withheld", sixDigits(r.shrink_withheld) },
                   { "text", r.verdict_text } };
  j["localised"] = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < r.where_held.size(); ++i)
  {
    const double z_after = i < r.where_held_after.size() ? r.where_held_after[i] : NAN;
    j["localised"].push_back({ { "where", departureJson(r.where_held[i]) }, { "z_after", sixDigits(z_after) } });
  }
  j["truth"] = { { "compared", r.has_truth }, { "departures", departuresJson(r.truth_where) } };
  j["seconds"] = sixDigits(r.seconds);
  return j;
}

std::string reportSummary(const Report& r)
{
  std::ostringstream o;
  char buf[512];
  std::snprintf(buf, sizeof(buf), "diagnose_gap: %s vs scenario '%s': %zu samples, %.6g Hz, %.1f s\n",
                r.real_source.c_str(), r.scenario_name.c_str(), r.samples, r.rate, r.duration);
  o << buf;
  std::snprintf(
      buf, sizeof(buf), "MOTION: %s; fitted: %s (withheld gap %.3g against the scenario as given, %.3g fitted)\n",
      r.motion.differs ? "differs" : "as the scenario's",
      r.motion.adopted.empty() ? "nothing" : r.motion.adopted.c_str(), r.motion.gap_before, r.motion.gap_after);
  o << buf;
  for (const std::string& finding : r.motion.findings)
    o << "  " << finding << "\n";
  if (!r.motion.left_out.empty())
    o << "  the fitted motion leaves the withheld part unexplained: " << r.motion.left_out.size()
      << " features it reaches and does not fit are left out of the sensor diagnosis\n";
  std::snprintf(buf, sizeof(buf),
                "WHERE (whole recording): gap %.3g (ensemble member vs rest: up to %.3g), %zu departures; largest:\n",
                r.gap_all, r.null_gap, r.where.size());
  o << buf;
  for (std::size_t i = 0; i < std::min<std::size_t>(8, r.where.size()); ++i)
  {
    const Departure& d = r.where[i];
    std::snprintf(buf, sizeof(buf), "  %-10s %-13s %-20s %-8s %-11s z %+9.3g (real %.4g, sim %.4g)\n",
                  d.where.channel.c_str(), d.where.quantity.c_str(), d.where.range.c_str(), d.where.segment.c_str(),
                  d.where.stage.c_str(), d.z, d.real, d.sim_median);
    o << buf;
  }
  auto timed = [&o, &buf](const char* title, const std::vector<Departure>& list) {
    std::snprintf(buf, sizeof(buf), "%s: %zu departures\n", title, list.size());
    o << buf;
    for (std::size_t i = 0; i < std::min<std::size_t>(3, list.size()); ++i)
    {
      const Departure& d = list[i];
      std::snprintf(buf, sizeof(buf), "  %-8s %-15s %-16s z %+9.3g (real %.4g, sim %.4g)\n", d.where.channel.c_str(),
                    d.where.quantity.c_str(), d.where.range.c_str(), d.z, d.real, d.sim_median);
      o << buf;
    }
  };
  timed("COMPENSATOR (its pipeline stages on real vs on the ensemble)", r.stage_where);
  if (r.has_truth)
  {
    timed("TRUTH (real minus the ideal IMU of its truth, against the ensemble's own)", r.truth_where);
  }
  o << "DIRECT:";
  for (const auto& d : r.direct)
  {
    o << " " << d.effect << "=" << (d.detected ? "yes" : "no");
  }
  o << "\nWHICH (fit on first part, gap on withheld part; before " << num(r.gap_before) << ", null "
    << num(r.null_gap_held) << "):\n";
  for (std::size_t i = 0; i < std::min<std::size_t>(8, r.ranking.size()); ++i)
  {
    const Candidate& c = r.ranking[i];
    std::snprintf(buf, sizeof(buf), "  %-34s gap %.3g -> %.3g  shrink %+6.1f %%  own %+4.0f %% of %-4d %.150s%s\n",
                  c.effect.c_str(), c.gap_before, c.gap_after, 100 * c.shrink, 100 * c.own.shrink, c.own.moved,
                  c.params.dump().c_str(), c.at_limit.empty() ? "" : "  [at a search limit]");
    o << buf;
  }
  std::snprintf(buf, sizeof(buf), "VERDICT: %s (confidence %.2f, shrink on withheld %.0f %%)\n  params %s\n  %s\n",
                r.verdict_effect.c_str(), r.confidence, 100 * r.shrink_withheld, r.verdict_params.dump().c_str(),
                r.verdict_text.c_str());
  o << buf;
  std::snprintf(buf, sizeof(buf), "(%.1f s)\n", r.seconds);
  o << buf;
  return o.str();
}
}  // namespace periodic_bias_compensation::gap
