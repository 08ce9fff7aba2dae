// The diagnosis: ensemble of the scenario as given, "where" departures, effect candidates
// fitted on the first part, re-simulated and judged on the withheld part, verdict, reports.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "periodic_bias_compensation/gap/gap.h"
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

std::string str(const std::string& s)
{
  std::string o = "\"";
  for (char c : s)
  {
    if (c == '"' || c == '\\')
    {
      o += '\\';
      o += c;
    }
    else if (c == '\n')
    {
      o += "\\n";
    }
    else
    {
      o += c;
    }
  }
  return o + "\"";
}

std::string departureJson(const Departure& d)
{
  std::ostringstream o;
  o << "{\"axis\": " << str(d.where.channel) << ", \"quantity\": " << str(d.where.quantity)
    << ", \"range\": " << str(d.where.range) << ", \"segment\": " << str(d.where.segment)
    << ", \"stage\": " << str(d.where.stage) << ", \"real\": " << num(d.real) << ", \"sim_median\": " << num(d.sim_median)
    << ", \"size_z\": " << num(d.z) << "}";
  return o.str();
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

/// Members of an ensemble: features of the withheld part of each run.
struct Ensemble
{
  std::vector<std::vector<double>> held;
  EnsembleStats stats;
};

/// Equivalence classes of effects whose outputs are the same signal (a line is a line).
bool equivalent(const std::string& a, const std::string& b)
{
  auto line = [](const std::string& e) { return e == "periodic_bias" || e == "vibration"; };
  return a == b || (line(a) && line(b));
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
  Recording real = real_in;
  if (real.rate <= 0.0)
  {
    real.rate = estimateRate(real);
  }
  if (real.size() < 200 || real.rate <= 0.0)
  {
    throw std::runtime_error("recording too short for a diagnosis (" + std::to_string(real.size()) + " samples)");
  }
  sim::Scenario scenario = matchScenario(scenario_in, real);
  sim::validateScenario(scenario);
  rep.real_source = real.source;
  rep.scenario_name = scenario.name;
  rep.rate = real.rate;
  rep.duration = real.stamp.back() - real.stamp.front();
  rep.samples = real.size();
  const int M = std::max(3, opt.ensemble);
  auto seedOf = [&opt](int i) { return opt.seed_base + static_cast<std::uint64_t>(i); };

  // Base ensemble, whole recordings. With a truth in the recording, each run's residual against
  // its own truth (then dropped: it is large) is reduced to the truth features at once.
  const bool truth = real.truth.size() >= 3;
  const int truth_blocks = 64;
  std::vector<std::vector<double>> truth_members(truth ? M : 0);
  std::vector<Eigen::MatrixXd> truth_runs(truth ? M : 0);
  // Plot curves of the base runs (withheld part) are taken on the way.
  const Recording real_held = sliceFraction(real, opt.fit_fraction, 1.0);
  const std::size_t n_held = real_held.size();
  const int nseg = welchSegment(n_held);
  std::vector<int> ms;
  for (int m = 1; static_cast<std::size_t>(m) * 10 <= n_held; m *= 2)
  {
    ms.push_back(m);
  }
  std::vector<Curves> cb(M);
  std::vector<std::vector<double>> stage_members(M);
  std::vector<Recording> base(M);
  const auto simulateBase = [&]() {
    parallelFor(M, opt.threads, [&](int i) {
      base[i] = simulateRecording(scenario, seedOf(i), truth);
      base[i].rate = real.rate;
      cb[i] = curvesOf(base[i], opt.fit_fraction, real.rate, nseg, ms);
      if (truth)
      {
        const Eigen::MatrixXd res = truthResidual(base[i], scenario.gravity, opt.truth_smooth);
        truth_members[i] = truthFeatures(res, opt.truth_segments);
        truth_runs[i] = blockMeans(res, truth_blocks);
        base[i].truth = TruthTrack();
      }
    });
  };
  simulateBase();
  const bool orient = real.has_orientation;
  const bool temp = real.has_temperature && scenario.temperature.enabled;
  rep.layout_held = makeLayout(real.rate, n_held, orient, temp);
  rep.real_held = computeFeatures(real_held, rep.layout_held);

  // 0. Motion: a tilt, heading or sea state of its own is fitted before any sensor effect; the
  // fit that brings the withheld part closest becomes the scenario of the base ensemble.
  const auto heldGap = [&](const std::vector<Recording>& runs) {
    std::vector<std::vector<double>> members(runs.size());
    parallelFor(static_cast<int>(runs.size()), opt.threads, [&](int i) {
      members[i] = computeFeatures(sliceFraction(runs[i], opt.fit_fraction, 1.0), rep.layout_held);
    });
    return gapOf(zScores(rep.real_held, ensembleStats(members, rep.layout_held)));
  };
  rep.motion = fitMotion(real, scenario, base);
  if (rep.motion.differs)
  {
    rep.motion.gap_before = heldGap(base);
    double best = rep.motion.gap_before;
    for (const MotionCandidate& candidate : rep.motion.candidates)
    {
      std::vector<Recording> runs(M);
      parallelFor(M, opt.threads, [&](int i) { runs[i] = simulateRecording(candidate.scenario, seedOf(i)); });
      const double gap = heldGap(runs);
      if (gap < best)
      {
        best = gap;
        rep.motion.adopted = candidate.what;
        rep.motion.fitted = candidate.scenario;
      }
    }
    if (!rep.motion.adopted.empty())
    {
      scenario = rep.motion.fitted;
      simulateBase();
    }
  }
  {
    // The compensator's pipeline stages on the real recording against the same on every run.
    // One run at a time: the core plans FFTW transforms, and FFTW planning is not thread-safe.
    for (int i = 0; i < M; ++i)
    {
      stage_members[i] = stageFeatures(base[i], 4);
    }
    const FeatureLayout sl = stageLayout(rep.duration, 4);
    rep.stage_where = rankDepartures(stageFeatures(real, 4), ensembleStats(stage_members, sl), sl);
  }
  if (truth)
  {
    rep.has_truth = true;
    const Eigen::MatrixXd res = truthResidual(real, scenario.gravity, opt.truth_smooth);
    const FeatureLayout tl = truthLayout(rep.duration, opt.truth_segments);
    rep.truth_where = rankDepartures(truthFeatures(res, opt.truth_segments), ensembleStats(truth_members, tl), tl);
    rep.truth_csv = "channel,t,real,sim_lo,sim_med,sim_hi\n" + blockCsv(blockMeans(res, truth_blocks), truth_runs, rep.duration);
  }

  // 1. Where: whole recording.
  rep.layout_all = makeLayout(real.rate, real.size(), orient, temp);
  rep.real_all = computeFeatures(real, rep.layout_all);
  std::vector<std::vector<double>> all(M);
  parallelFor(M, opt.threads, [&](int i) { all[i] = computeFeatures(base[i], rep.layout_all); });
  rep.ens_all = ensembleStats(all, rep.layout_all);
  rep.where = rankDepartures(rep.real_all, rep.ens_all, rep.layout_all);
  rep.where.insert(rep.where.end(), rep.truth_where.begin(), rep.truth_where.end());
  rep.where.insert(rep.where.end(), rep.stage_where.begin(), rep.stage_where.end());
  std::stable_sort(rep.where.begin(), rep.where.end(),
                   [](const Departure& a, const Departure& b) { return std::abs(a.z) > std::abs(b.z); });
  rep.gap_all = gapOf(zScores(rep.real_all, rep.ens_all));
  for (int i = 0; i < M; ++i)
  {
    std::vector<std::vector<double>> rest;
    for (int j = 0; j < M; ++j)
    {
      if (j != i)
      {
        rest.push_back(all[j]);
      }
    }
    rep.null_gap = std::max(rep.null_gap, gapOf(zScores(all[i], ensembleStats(rest, rep.layout_all))));
  }

  // 2. Withheld part: layout, base ensemble.
  const Recording real_fit = sliceFraction(real, 0.0, opt.fit_fraction);
  std::vector<Recording> base_fit(M);
  rep.ens_held_members.resize(M);
  parallelFor(M, opt.threads, [&](int i) {
    base_fit[i] = sliceFraction(base[i], 0.0, opt.fit_fraction);
    rep.ens_held_members[i] = computeFeatures(sliceFraction(base[i], opt.fit_fraction, 1.0), rep.layout_held);
  });
  base.clear();
  rep.ens_held = ensembleStats(rep.ens_held_members, rep.layout_held);
  const std::vector<double> z_before = zScores(rep.real_held, rep.ens_held);
  rep.gap_before = gapOf(z_before);
  rep.motion.gap_after = rep.gap_before;
  if (rep.motion.adopted.empty())
  {
    rep.motion.gap_before = rep.gap_before;
  }
  std::vector<double> null_gaps;
  for (int i = 0; i < M; ++i)
  {
    std::vector<std::vector<double>> rest;
    for (int j = 0; j < M; ++j)
    {
      if (j != i)
      {
        rest.push_back(rep.ens_held_members[j]);
      }
    }
    const std::vector<double> zn = zScores(rep.ens_held_members[i], ensembleStats(rest, rep.layout_held));
    rep.null_gap_held = std::max(rep.null_gap_held, gapOf(zn));
    null_gaps.push_back(gapOf(zn));
    for (double v : zn)
    {
      rep.null_max_z_held = std::max(rep.null_max_z_held, std::abs(v));
    }
  }
  std::sort(null_gaps.begin(), null_gaps.end());
  rep.null_gap_typical = null_gaps[null_gaps.size() / 2];
  for (double v : z_before)
  {
    rep.max_z_held = std::max(rep.max_z_held, std::abs(v));
  }

  // Direct detections (stamps, lattice, clipping, gaps) on the whole recording.
  {
    const StampStats st = stampStats(real.stamp, real.rate);
    char buf[256];
    std::snprintf(buf, sizeof(buf), "stamp residual robust std %.3g s (rate %.6g Hz), %.0f backwards", st.jitter, st.rate,
                  st.backwards);
    rep.direct.push_back({ "timestamp_jitter", st.jitter > 0.02 / real.rate, buf });
    std::snprintf(buf, sizeof(buf), "%.3g %% of samples missing in %.0f gaps (mean %.3g samples)", 100 * st.lost_fraction,
                  st.bursts, st.mean_burst);
    rep.direct.push_back({ "dropouts", st.bursts > 0, buf });
    const double repeated = repeatedFraction(real.data);
    std::snprintf(buf, sizeof(buf), "%.3g %% of the samples repeat their predecessor in all six channels", 100 * repeated);
    rep.direct.push_back({ "sample_hold", repeated > 0.02, buf });
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
    rep.direct.push_back({ "quantization", any_lat, "lattice step per axis (0 = none): " + lat });
    rep.direct.push_back({ "saturation", any_clip, "samples at the largest magnitude: " + clip });
  }

  // 3. Candidates fitted on the first part, judged on the withheld part.
  std::vector<Candidate> cands = fitCandidates(real_fit, base_fit, scenario);
  base_fit.clear();
  auto judge = [&](std::vector<Candidate>& list) {
    const int nc = static_cast<int>(list.size());
    std::vector<std::vector<std::vector<double>>> feats(nc, std::vector<std::vector<double>>(M));
    std::vector<std::string> errors(nc);
    parallelFor(nc * M, opt.threads, [&](int idx) {
      const int c = idx / M, i = idx % M;
      try
      {
        const sim::Scenario s = withCandidate(scenario, list[c].specs);
        Recording r = simulateRecording(s, seedOf(i));
        r.rate = real.rate;
        feats[c][i] = computeFeatures(sliceFraction(r, opt.fit_fraction, 1.0), rep.layout_held);
      }
      catch (const std::exception& e)
      {
        errors[c] = e.what();
      }
    });
    for (int c = 0; c < nc; ++c)
    {
      list[c].gap_before = rep.gap_before;
      if (!errors[c].empty())
      {
        list[c].note += " (not simulated: " + errors[c] + ")";
        list[c].gap_after = rep.gap_before;
        list[c].shrink = 0.0;
        continue;
      }
      const EnsembleStats st = ensembleStats(feats[c], rep.layout_held);
      list[c].z_after = zScores(rep.real_held, st);
      list[c].gap_after = gapOf(list[c].z_after, st.spread, rep.ens_held.spread);
      const double excess = rep.gap_before - rep.null_gap_typical;
      list[c].shrink = excess > 0 ? std::min(1.0, (rep.gap_before - list[c].gap_after) / excess) : 0.0;
    }
  };
  judge(cands);
  std::sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) { return a.shrink > b.shrink; });

  // A pure spectral line is the same signal for periodic_bias and vibration: when the twin
  // explains at least half as much, name the line by its frequency (below 1 Hz a periodic bias,
  // above a vibration: the vocabulary's slow bias and engine line).
  if (!cands.empty() && (cands[0].effect == "periodic_bias" || cands[0].effect == "vibration"))
  {
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
    const std::string want = f > 1.0 ? "vibration" : "periodic_bias";
    if (twin > 0 && f >= 0.0 && cands[twin].effect == want)
    {
      std::rotate(cands.begin(), cands.begin() + static_cast<std::ptrdiff_t>(twin), cands.begin() + static_cast<std::ptrdiff_t>(twin) + 1);
    }
  }
  // A random walk and a Gauss-Markov bias both explain a wandering bias. Name the simpler random
  // walk (no correlation time) when it explains about as much (within 0.06), or when the
  // fitted correlation time exceeds half the recording (over that recording, a random walk) and
  // it explains nearly as much (within 0.15). A Gauss-Markov bias whose correlation time shows
  // in the recording leaves the random walk clearly behind (0.15-0.25 in validate_gap).
  if (cands.size() >= 2 && cands[0].effect == "bias_instability" && !cands[0].specs.empty())
  {
    const double tc = cands[0].specs.back().params.at("correlation_time")[0];
    for (std::size_t i = 1; i < cands.size(); ++i)
    {
      const double behind = cands[0].shrink - cands[i].shrink;
      if (cands[i].effect == "bias_random_walk" && (behind < 0.06 || (tc > 0.5 * rep.duration && behind < 0.15)))
      {
        std::rotate(cands.begin(), cands.begin() + static_cast<std::ptrdiff_t>(i), cands.begin() + static_cast<std::ptrdiff_t>(i) + 1);
        break;
      }
    }
  }
  // Best pair of two different effects, if it explains clearly more.
  if (cands.size() >= 2 && cands[0].shrink > 0)
  {
    std::size_t j = 1;
    while (j < cands.size() && equivalent(cands[0].effect, cands[j].effect))
    {
      ++j;
    }
    if (j < cands.size() && cands[j].shrink > 0)
    {
      Candidate pair;
      pair.effect = cands[0].effect + "+" + cands[j].effect;
      pair.specs = cands[0].specs;
      pair.specs.insert(pair.specs.end(), cands[j].specs.begin(), cands[j].specs.end());
      pair.params_json = "{\"" + cands[0].effect + "\": " + cands[0].params_json + ", \"" + cands[j].effect +
                         "\": " + cands[j].params_json + "}";
      pair.note = "best two together";
      std::vector<Candidate> one{ pair };
      judge(one);
      if (one[0].shrink > cands[0].shrink + opt.pair_gain)
      {
        cands.insert(cands.begin(), one[0]);
      }
      else
      {
        cands.push_back(one[0]);
      }
    }
  }
  rep.ranking = cands;

  // Verdict.
  const double significant_gap = std::max(1.5 * rep.null_gap_held, 0.05);
  const bool significant = rep.gap_before > significant_gap ||
                           rep.max_z_held > std::max(1.5 * rep.null_max_z_held, 2.0 * kZThreshold);
  if (!significant)
  {
    rep.verdict_effect = "no_gap";
    rep.verdict_params = "{}";
    rep.confidence = 0.0;
    rep.verdict_text = "no significant gap: the recording lies within the simulated ensemble's spread";
  }
  else if (rep.ranking.empty() || rep.ranking[0].shrink < opt.min_shrink)
  {
    rep.verdict_effect = "none";
    rep.verdict_params = "{}";
    rep.confidence = 0.0;
    rep.shrink_withheld = rep.ranking.empty() ? 0.0 : rep.ranking[0].shrink;
    rep.verdict_text = "no candidate explains the gap (best shrink below " + num(opt.min_shrink) + "); the residual is reported in 'where'";
  }
  else
  {
    const Candidate& b = rep.ranking[0];
    double second = 0.0;
    for (std::size_t i = 1; i < rep.ranking.size(); ++i)
    {
      const std::string& e = rep.ranking[i].effect;
      if (!equivalent(e, b.effect) && b.effect.find(e) == std::string::npos && e.find('+') == std::string::npos)
      {
        second = std::max(second, rep.ranking[i].shrink);
      }
    }
    rep.best = 0;
    rep.verdict_effect = b.effect;
    rep.verdict_params = b.params_json;
    rep.shrink_withheld = b.shrink;
    const double margin = b.shrink - std::max(0.0, second);
    rep.confidence = std::max(0.0, std::min(1.0, b.shrink)) * std::max(0.0, std::min(1.0, 0.4 + margin / 0.4));
    rep.verdict_text = b.effect + " explains " + num(100.0 * b.shrink) + " % of the gap on the withheld part";
  }
  // Localised places of the withheld part, before and after the verdict.
  rep.where_held = rankDepartures(rep.real_held, rep.ens_held, rep.layout_held, kZThreshold, 12);
  if (rep.best >= 0)
  {
    const Candidate* best = &rep.ranking[rep.best];
    for (const Departure& d : rep.where_held)
    {
      for (std::size_t i = 0; i < rep.layout_held.info.size(); ++i)
      {
        const FeatureInfo& f = rep.layout_held.info[i];
        if (f.channel == d.where.channel && f.quantity == d.where.quantity && f.range == d.where.range &&
            f.segment == d.where.segment)
        {
          rep.where_held_after.push_back(best->z_after.empty() ? 0.0 : best->z_after[i]);
          break;
        }
      }
    }
  }
  // Curves for plots: PSD and Allan of the withheld part (real, ensemble median, ensemble with
  // the verdict), block means of the whole recording (drift).
  {
    std::vector<sim::EffectSpec> specs;
    if (rep.best >= 0)
    {
      specs = rep.ranking[rep.best].specs;
    }
    const sim::Scenario eff = withCandidate(scenario, specs);
    const Curves cr = curvesOf(real, opt.fit_fraction, real.rate, nseg, ms);
    std::vector<Curves> ce(M);
    parallelFor(M, opt.threads, [&](int i) {
      Recording r = simulateRecording(eff, seedOf(i));
      r.rate = real.rate;
      ce[i] = curvesOf(r, opt.fit_fraction, real.rate, nseg, ms);
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
        for (int i = 0; i < M; ++i)
        {
          vb.push_back(cb[i].psd[ch].power[k]);
          ve.push_back(ce[i].psd[ch].power[k]);
        }
        ps << name << "," << num(k * cr.psd[ch].df) << "," << num(cr.psd[ch].power[k]) << "," << num(med(vb)) << ","
           << num(med(ve)) << "\n";
      }
      for (std::size_t k = 0; k < ms.size(); ++k)
      {
        std::vector<double> vb, ve;
        for (int i = 0; i < M; ++i)
        {
          vb.push_back(cb[i].adev[ch][k]);
          ve.push_back(ce[i].adev[ch][k]);
        }
        as << name << "," << num(ms[k] / real.rate) << "," << num(cr.adev[ch][k]) << "," << num(med(vb)) << ","
           << num(med(ve)) << "\n";
      }
    }
    rep.psd_csv = ps.str();
    rep.allan_csv = as.str();
    std::vector<Eigen::MatrixXd> bb, be;
    for (int i = 0; i < M; ++i)
    {
      bb.push_back(cb[i].blocks);
      be.push_back(ce[i].blocks);
    }
    rep.drift_csv = "channel,t,real,sim_lo,sim_med,sim_hi,sim_effect_med\n" + blockCsv(cr.blocks, bb, rep.duration, &be);
    std::ostringstream fs;
    fs << "index,channel,quantity,range,segment,lo,hi,real,sim,spread,z_before,z_after\n";
    for (std::size_t i = 0; i < rep.layout_held.info.size(); ++i)
    {
      const FeatureInfo& f = rep.layout_held.info[i];
      fs << i << "," << f.channel << "," << f.quantity << ",\"" << f.range << "\"," << f.segment << "," << num(f.lo) << ","
         << num(f.hi) << "," << num(rep.real_held[i]) << "," << num(rep.ens_held.median[i]) << ","
         << num(rep.ens_held.spread[i]) << "," << num(z_before[i]) << ","
         << num(rep.best >= 0 && !rep.ranking[rep.best].z_after.empty() ? rep.ranking[rep.best].z_after[i] : z_before[i]) << "\n";
    }
    rep.features_csv = fs.str();
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return rep;
}

namespace
{
std::string motionSummaryJson(const MotionSummary& m)
{
  std::ostringstream o;
  o << "{\"roll\": " << num(m.roll) << ", \"pitch\": " << num(m.pitch) << ", \"heading\": "
    << (std::isfinite(m.heading) ? num(m.heading) : std::string("null")) << ", \"wave_height\": " << num(m.wave_height)
    << ", \"peak_period\": " << num(m.peak_period) << "}";
  return o.str();
}

std::string motionJson(const MotionFit& m)
{
  std::ostringstream o;
  o << "{\"differs\": " << (m.differs ? "true" : "false") << ", \"adopted\": " << str(m.adopted)
    << ",\n    \"real\": " << motionSummaryJson(m.real) << ",\n    \"scenario\": " << motionSummaryJson(m.scenario)
    << ",\n    \"findings\": [";
  for (std::size_t i = 0; i < m.findings.size(); ++i)
    o << (i ? ", " : "") << str(m.findings[i]);
  o << "], \"gap_before\": " << num(m.gap_before) << ", \"gap_after\": " << num(m.gap_after) << "}";
  return o.str();
}
}  // namespace

std::string reportJson(const Report& r)
{
  std::ostringstream o;
  o << "{\n  \"schema\": \"periodic_bias_compensation/gap_report/1\",\n";
  o << "  \"real\": {\"source\": " << str(r.real_source) << ", \"rate_hz\": " << num(r.rate)
    << ", \"duration_s\": " << num(r.duration) << ", \"samples\": " << r.samples << "},\n";
  o << "  \"scenario\": " << str(r.scenario_name) << ",\n";
  o << "  \"motion\": " << motionJson(r.motion) << ",\n";
  o << "  \"gap_metric\": \"rms over features of log(1 + max(0, |z| - 3)), z = (real - ensemble median) / ensemble spread\",\n";
  o << "  \"gap_all\": " << num(r.gap_all) << ", \"null_gap_all\": " << num(r.null_gap) << ",\n";
  o << "  \"where\": [";
  for (std::size_t i = 0; i < r.where.size(); ++i)
  {
    o << (i ? ",\n    " : "\n    ") << departureJson(r.where[i]);
  }
  o << "\n  ],\n";
  o << "  \"direct\": [";
  for (std::size_t i = 0; i < r.direct.size(); ++i)
  {
    o << (i ? ",\n    " : "\n    ") << "{\"effect\": " << str(r.direct[i].effect)
      << ", \"detected\": " << (r.direct[i].detected ? "true" : "false") << ", \"evidence\": " << str(r.direct[i].evidence)
      << "}";
  }
  o << "\n  ],\n";
  o << "  \"withheld\": {\"gap_before\": " << num(r.gap_before) << ", \"null_gap\": " << num(r.null_gap_held)
    << ", \"null_gap_typical\": " << num(r.null_gap_typical)
    << ", \"max_z\": " << num(r.max_z_held) << ", \"null_max_z\": " << num(r.null_max_z_held) << "},\n";
  o << "  \"ranking\": [";
  for (std::size_t i = 0; i < r.ranking.size(); ++i)
  {
    const Candidate& c = r.ranking[i];
    o << (i ? ",\n    " : "\n    ") << "{\"effect\": " << str(c.effect) << ", \"params\": " << (c.params_json.empty() ? "{}" : c.params_json)
      << ", \"gap_before\": " << num(c.gap_before) << ", \"gap_after\": " << num(c.gap_after)
      << ", \"shrink\": " << num(c.shrink) << ", \"fit\": " << str(c.note) << "}";
  }
  o << "\n  ],\n";
  o << "  \"verdict\": {\"effect\": " << str(r.verdict_effect) << ", \"params\": " << r.verdict_params
    << ", \"confidence\": " << num(r.confidence) << ", \"shrink_withheld\": " << num(r.shrink_withheld)
    << ", \"text\": " << str(r.verdict_text) << "},\n";
  o << "  \"localised\": [";
  for (std::size_t i = 0; i < r.where_held.size(); ++i)
  {
    o << (i ? ",\n    " : "\n    ") << "{\"where\": " << departureJson(r.where_held[i])
      << ", \"z_after\": " << (i < r.where_held_after.size() ? num(r.where_held_after[i]) : "null") << "}";
  }
  o << "\n  ],\n";
  o << "  \"truth\": {\"compared\": " << (r.has_truth ? "true" : "false") << ", \"departures\": [";
  for (std::size_t i = 0; i < r.truth_where.size(); ++i)
  {
    o << (i ? ",\n    " : "\n    ") << departureJson(r.truth_where[i]);
  }
  o << "]},\n";
  o << "  \"seconds\": " << num(r.seconds) << "\n}\n";
  return o.str();
}

std::string reportSummary(const Report& r)
{
  std::ostringstream o;
  char buf[512];
  std::snprintf(buf, sizeof(buf), "diagnose_gap: %s vs scenario '%s': %zu samples, %.6g Hz, %.1f s\n",
                r.real_source.c_str(), r.scenario_name.c_str(), r.samples, r.rate, r.duration);
  o << buf;
  std::snprintf(buf, sizeof(buf), "MOTION: %s; fitted: %s (withheld gap %.3g against the scenario as given, %.3g fitted)\n",
                r.motion.differs ? "differs" : "as the scenario's", r.motion.adopted.empty() ? "nothing" : r.motion.adopted.c_str(),
                r.motion.gap_before, r.motion.gap_after);
  o << buf;
  for (const std::string& finding : r.motion.findings)
    o << "  " << finding << "\n";
  std::snprintf(buf, sizeof(buf), "WHERE (whole recording): gap %.3g (ensemble member vs rest: up to %.3g), %zu departures; largest:\n",
                r.gap_all, r.null_gap, r.where.size());
  o << buf;
  for (std::size_t i = 0; i < std::min<std::size_t>(8, r.where.size()); ++i)
  {
    const Departure& d = r.where[i];
    std::snprintf(buf, sizeof(buf), "  %-10s %-13s %-20s %-8s %-11s z %+9.3g (real %.4g, sim %.4g)\n", d.where.channel.c_str(),
                  d.where.quantity.c_str(), d.where.range.c_str(), d.where.segment.c_str(), d.where.stage.c_str(), d.z,
                  d.real, d.sim_median);
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
  o << "\nWHICH (fit on first part, gap on withheld part; before " << num(r.gap_before) << ", null " << num(r.null_gap_held)
    << "):\n";
  for (std::size_t i = 0; i < std::min<std::size_t>(8, r.ranking.size()); ++i)
  {
    const Candidate& c = r.ranking[i];
    std::snprintf(buf, sizeof(buf), "  %-34s gap %.3g -> %.3g  shrink %+6.1f %%  %.150s\n", c.effect.c_str(), c.gap_before,
                  c.gap_after, 100 * c.shrink, c.params_json.c_str());
    o << buf;
  }
  std::snprintf(buf, sizeof(buf), "VERDICT: %s (confidence %.2f, shrink on withheld %.0f %%)\n  params %s\n  %s\n",
                r.verdict_effect.c_str(), r.confidence, 100 * r.shrink_withheld, r.verdict_params.c_str(),
                r.verdict_text.c_str());
  o << buf;
  std::snprintf(buf, sizeof(buf), "(%.1f s)\n", r.seconds);
  o << buf;
  return o.str();
}
}  // namespace periodic_bias_compensation::gap
