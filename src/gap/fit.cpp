// Effect candidates: for each effect of the simulator's vocabulary, closed-form or moment
// estimates of its parameters from the difference between the real recording and the
// simulated ensemble of the scenario as given (first part of the recording only).
//
// Every candidate is a list of EffectSpec that REPLACES all occurrences of that effect in the
// scenario; additive effects carry the scenario's own value plus the fitted difference.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include <Eigen/Dense>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/gap/diagnose.h"
#include "periodic_bias_compensation/gap/features.h"
#include "periodic_bias_compensation/gap/signal.h"
#include "periodic_bias_compensation/sim/effects.h"

namespace periodic_bias_compensation::gap
{
namespace
{
using Vec = std::vector<double>;

double meanOf(const Vec& v)
{
  double s = 0.0;
  for (double a : v)
  {
    s += a;
  }
  return v.empty() ? 0.0 : s / v.size();
}

double stdOf(const Vec& v)
{
  if (v.size() < 2)
  {
    return 0.0;
  }
  const double m = meanOf(v);
  double s = 0.0;
  for (double a : v)
  {
    s += (a - m) * (a - m);
  }
  return std::sqrt(s / (v.size() - 1));
}

/// The upper median (0 when empty).
double medianOf(Vec v)
{
  return v.empty() ? 0.0 : upperMedian(v.begin(), v.end());
}

/// The parameters of an effect: a number, or a list for vector parameters.
nlohmann::ordered_json paramsJson(const sim::EffectSpec& spec)
{
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [k, v] : spec.params)
  {
    nlohmann::ordered_json values = nlohmann::ordered_json::array();
    for (double a : v)
    {
      values.push_back(sixDigits(a));
    }
    j[k] = v.size() == 1 ? values[0] : values;
  }
  return j;
}

/// Enabled occurrences of an effect in the scenario, completed with defaults.
std::vector<sim::EffectSpec> existing(const sim::Scenario& s, const std::string& name)
{
  std::vector<sim::EffectSpec> out;
  for (const auto& e : s.effects)
  {
    if (e.name == name && e.enabled)
    {
      out.push_back(sim::completeEffect(e));
    }
  }
  return out;
}

/// Sum over occurrences of a per-axis (or any-size) parameter.
Vec sumParam(const std::vector<sim::EffectSpec>& specs, const std::string& key, std::size_t size)
{
  Vec v(size, 0.0);
  for (const auto& e : specs)
  {
    const auto it = e.params.find(key);
    if (it != e.params.end())
    {
      for (std::size_t i = 0; i < size && i < it->second.size(); ++i)
      {
        v[i] += it->second[i];
      }
    }
  }
  return v;
}

Vec sumSquares(const std::vector<sim::EffectSpec>& specs, const std::string& key)
{
  Vec v(3, 0.0);
  for (const auto& e : specs)
  {
    const auto it = e.params.find(key);
    if (it != e.params.end())
    {
      for (std::size_t i = 0; i < 3 && i < it->second.size(); ++i)
      {
        v[i] += it->second[i] * it->second[i];
      }
    }
  }
  return v;
}

bool anyNonZero(const Vec& v)
{
  for (double a : v)
  {
    if (a != 0.0)
    {
      return true;
    }
  }
  return false;
}

/// Everything the fits use, for one recording.
struct FitStats
{
  Vec mean = Vec(kChannels, 0.0);
  std::vector<Psd> psd;                               ///< per channel
  std::vector<Psd> psd_fine;                          ///< per channel, long segments (spectral lines)
  std::vector<Vec> avar;                              ///< per channel, Allan variance at allan_m
  std::array<std::vector<Eigen::Matrix3d>, 2> cross;  ///< accel, gyro
  StampStats stamps;
  Vec lattice = Vec(kChannels, 0.0);
  Vec flat = Vec(kChannels, 0.0);
  Vec limit = Vec(kChannels, 0.0);
  double repeated = 0.0;  ///< rows equal to their predecessor [-]
  Vec temp_slope = Vec(kChannels, 0.0);
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
  bool lever_ok = false;
  double leak_e = 0.0, leak_n = 0.0, yaw = 0.0;
  bool has_leak = false;
};

/// Least-squares lever arm: accel ~ c + (alpha x r + omega x (omega x r)), omega from the gyro.
bool leverArm(const Recording& r, double rate, Eigen::Vector3d* out)
{
  const std::size_t n = r.size();
  if (n < 50)
  {
    return false;
  }
  const int w = std::max(1, static_cast<int>(std::lround(rate * 0.05)));
  // moving averages
  Eigen::MatrixXd sm(n, kChannels);
  Eigen::MatrixXd cs = Eigen::MatrixXd::Zero(n + 1, kChannels);
  for (std::size_t i = 0; i < n; ++i)
  {
    cs.row(i + 1) = cs.row(i) + r.data.row(i);
  }
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t a = i >= static_cast<std::size_t>(w) ? i - w : 0;
    const std::size_t b = std::min(n, i + w + 1);
    sm.row(i) = (cs.row(b) - cs.row(a)) / static_cast<double>(b - a);
  }
  Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  // First pass: means of A and a, for the intercept.
  std::vector<Eigen::Matrix3d> As;
  As.reserve(n);
  Eigen::Matrix3d Am = Eigen::Matrix3d::Zero();
  Eigen::Vector3d am = Eigen::Vector3d::Zero();
  const std::size_t step = 2 * w;
  for (std::size_t i = step; i + step < n; ++i)
  {
    const Eigen::Vector3d om = sm.row(i).tail<3>().transpose();
    const Eigen::Vector3d al =
        (sm.row(i + step).tail<3>() - sm.row(i - step).tail<3>()).transpose() * rate / (2.0 * step);
    Eigen::Matrix3d Ka, Ko;
    Ka << 0, -al.z(), al.y(), al.z(), 0, -al.x(), -al.y(), al.x(), 0;
    Ko << 0, -om.z(), om.y(), om.z(), 0, -om.x(), -om.y(), om.x(), 0;
    As.push_back(Ka + Ko * Ko);
    Am += As.back();
    am += sm.row(i).head<3>().transpose();
  }
  if (As.size() < 20)
  {
    return false;
  }
  Am /= static_cast<double>(As.size());
  am /= static_cast<double>(As.size());
  std::size_t j = 0;
  for (std::size_t i = step; i + step < n; ++i, ++j)
  {
    const Eigen::Matrix3d A = As[j] - Am;
    const Eigen::Vector3d a = sm.row(i).head<3>().transpose() - am;
    G += A.transpose() * A;
    h += A.transpose() * a;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(G);
  if (es.eigenvalues().minCoeff() <= 1e-12 * std::max(1.0, es.eigenvalues().maxCoeff()) ||
      es.eigenvalues().maxCoeff() / static_cast<double>(As.size()) < 1e-8)
  {
    return false;
  }
  *out = G.ldlt().solve(h);
  return out->allFinite();
}

int fineSegment(std::size_t n)
{
  int nseg = 16;
  while (static_cast<std::size_t>(nseg) * 2 <= n / 2 && nseg < (1 << 18))
  {
    nseg *= 2;
  }
  return nseg;
}

FitStats fitStats(const Recording& r, double rate, int nseg, const std::vector<int>& allan_m, bool want_temperature)
{
  FitStats s;
  const std::size_t n = r.size();
  for (int c = 0; c < kChannels; ++c)
  {
    const Eigen::VectorXd x = r.data.col(c);
    s.mean[c] = n ? x.mean() : 0.0;
    s.psd.push_back(welch(x, rate, nseg));
    s.psd_fine.push_back(welch(x, rate, fineSegment(n)));
    Vec ad = allanDeviation(x, allan_m);
    for (double& a : ad)
    {
      a = std::isfinite(a) ? a * a : 0.0;
    }
    s.avar.push_back(ad);
    s.lattice[c] = latticeStep(x);
    double lim = 0.0;
    s.flat[c] = flatTopFraction(x, &lim);
    s.limit[c] = lim;
  }
  s.repeated = repeatedFraction(r.data);
  s.cross[0] = welchCross3(r.data.leftCols(3), rate, nseg);
  s.cross[1] = welchCross3(r.data.rightCols(3), rate, nseg);
  s.stamps = stampStats(r.stamp, rate);
  s.lever_ok = leverArm(r, rate, &s.lever);
  if (r.has_orientation && r.orientation.size() == n && n > 0)
  {
    Eigen::Vector3d fe = Eigen::Vector3d::Zero();
    Eigen::Vector2d hd = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < n; ++i)
    {
      fe += r.orientation[i] * Eigen::Vector3d(r.data.row(i).head<3>().transpose());
      const Eigen::Vector3d xa = r.orientation[i] * Eigen::Vector3d::UnitX();
      hd += Eigen::Vector2d(xa.x(), xa.y());
    }
    fe /= static_cast<double>(n);
    const double g = std::max(fe.norm(), 1e-9);
    s.leak_e = fe.x() / g;
    s.leak_n = fe.y() / g;
    s.yaw = std::atan2(hd.y(), hd.x());
    s.has_leak = true;
  }
  if (want_temperature && r.has_temperature && r.temperature.size() == n && n > 64)
  {
    const int blocks = 32;
    for (int c = 0; c < kChannels; ++c)
    {
      Vec xb(blocks), tb(blocks);
      for (int k = 0; k < blocks; ++k)
      {
        const std::size_t a = n * k / blocks, b = n * (k + 1) / blocks;
        double sx = 0, st = 0;
        for (std::size_t i = a; i < b; ++i)
        {
          sx += r.data(i, c);
          st += r.temperature[i];
        }
        xb[k] = sx / (b - a);
        tb[k] = st / (b - a);
      }
      const double mx = meanOf(xb), mt = meanOf(tb);
      double cov = 0, var = 0;
      for (int k = 0; k < blocks; ++k)
      {
        cov += (xb[k] - mx) * (tb[k] - mt);
        var += (tb[k] - mt) * (tb[k] - mt);
      }
      s.temp_slope[c] = var > 1e-9 ? cov / var : 0.0;
    }
  }
  return s;
}

/// A channel quantity of the real recording, the ensemble mean and spread.
struct Cmp
{
  double real, sim, spread;
  bool significant(double k = 3.0, double abs_floor = 0.0) const
  {
    return std::abs(real - sim) > k * spread + abs_floor;
  }
};

/// Bins where the ensemble's PSD of a channel is motion (20 x above its high-frequency floor).
std::vector<std::size_t> motionBins(const std::vector<FitStats>& sims, int c)
{
  const std::size_t nb = sims[0].psd[c].power.size();
  Vec mean(nb, 0.0);
  for (const auto& s : sims)
  {
    for (std::size_t k = 0; k < nb; ++k)
    {
      mean[k] += s.psd[c].power[k] / sims.size();
    }
  }
  Vec hi(mean.begin() + nb / 2, mean.end());
  const double floor = medianOf(hi);
  std::vector<std::size_t> bins;
  for (std::size_t k = 1; k < nb; ++k)
  {
    if (mean[k] > 20.0 * floor && mean[k] > 0.0)
    {
      bins.push_back(k);
    }
  }
  return bins;
}

Vec meanPsd(const std::vector<FitStats>& sims, int c)
{
  const std::size_t nb = sims[0].psd_fine[c].power.size();
  Vec mean(nb, 0.0);
  for (const auto& s : sims)
  {
    for (std::size_t k = 0; k < nb; ++k)
    {
      mean[k] += s.psd_fine[c].power[k] / sims.size();
    }
  }
  return mean;
}

/// Strongest excess spectral line of a channel: bin, power [unit^2] (0 if none).
struct Line
{
  std::size_t bin = 0;
  double freq = 0.0;
  double power = 0.0;
  double ratio = 0.0;
  double width_bins = 0.0;
};

Line strongestLine(const Psd& real, const Vec& sim, double min_ratio, double min_freq = 0.0)
{
  Line best;
  const std::size_t nb = real.power.size();
  const std::size_t first = std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(min_freq / real.df)));
  for (std::size_t k = first; k + 1 < nb; ++k)
  {
    const double ratio = real.power[k] / std::max(sim[k], 1e-300);
    const double excess = real.power[k] - sim[k];
    if (ratio > min_ratio && excess > 0 && real.power[k] >= real.power[k - 1] && real.power[k] >= real.power[k + 1] &&
        excess > (best.power > 0 ? (real.power[best.bin] - sim[best.bin]) : 0.0))
    {
      best.bin = k;
      best.ratio = ratio;
      best.power = excess;
    }
  }
  if (best.bin == 0)
  {
    return Line{};
  }
  std::size_t a = best.bin, b = best.bin;
  while (a > 1 && real.power[a - 1] > 2.0 * sim[a - 1])
  {
    --a;
  }
  while (b + 1 < nb && real.power[b + 1] > 2.0 * sim[b + 1])
  {
    ++b;
  }
  a = std::min(a, best.bin - 1);
  b = std::max(b, best.bin + 1);
  double p = 0.0;
  for (std::size_t k = a; k <= b; ++k)
  {
    p += std::max(0.0, real.power[k] - sim[k]) * real.df;
  }
  best.power = p;
  best.width_bins = static_cast<double>(b - a + 1);
  // Parabolic interpolation of the log power for the frequency.
  const double l0 = std::log(std::max(real.power[best.bin - 1], 1e-300));
  const double l1 = std::log(std::max(real.power[best.bin], 1e-300));
  const double l2 = std::log(std::max(real.power[best.bin + 1], 1e-300));
  const double den = l0 - 2 * l1 + l2;
  const double delta = std::abs(den) > 1e-12 ? 0.5 * (l0 - l2) / den : 0.0;
  best.freq = (best.bin + std::max(-0.5, std::min(0.5, delta))) * real.df;
  return best;
}

/// The normal equations' sums of a least-squares sinusoid in a channel.
struct SinusoidSums
{
  double ss = 0, sc = 0, cc = 0, xs = 0, xc = 0;

  void add(double x, double s, double c)
  {
    ss += s * s;
    sc += s * c;
    cc += c * c;
    xs += x * s;
    xc += x * c;
  }

  /// Amplitude and phase of A sin(2 pi f t + phi) (0 and 0 when singular).
  void solve(double* amplitude, double* phase) const
  {
    const double det = ss * cc - sc * sc;
    if (std::abs(det) < 1e-12)
    {
      *amplitude = 0;
      *phase = 0;
      return;
    }
    const double a = (xs * cc - xc * sc) / det;  // coefficient of sin
    const double b = (xc * ss - xs * sc) / det;  // coefficient of cos
    *amplitude = std::hypot(a, b);
    *phase = std::atan2(b, a);
  }
};

/// Least-squares phase and amplitude of A sin(2 pi f t + phi) in a channel (t since the start).
void sinusoidFit(const Recording& r, int c, double f, double t0, double* amplitude, double* phase)
{
  SinusoidSums sums;
  const double m = r.data.col(c).mean();
  for (std::size_t i = 0; i < r.size(); ++i)
  {
    const double turns = f * (r.stamp[i] - t0);
    double s, co;
    sinCosTurn(turns - std::floor(turns), &s, &co);
    sums.add(r.data(i, c) - m, s, co);
  }
  sums.solve(amplitude, phase);
}

/// sinusoidFit at the frequencies f0 + k step for k = 0 .. n - 1, in one pass over the samples:
/// each sample's phasor at f0 is turned by its phasor at `step`, k times.
void sinusoidFitGrid(const Recording& r, int c, double f0, double step, int n, double t0,
                     std::vector<double>* amplitude, std::vector<double>* phase)
{
  std::vector<SinusoidSums> sums(n);
  const double m = r.data.col(c).mean();
  for (std::size_t i = 0; i < r.size(); ++i)
  {
    const double t = r.stamp[i] - t0, x = r.data(i, c) - m;
    const double turns = f0 * t, step_turns = step * t;
    double s, co, ds, dc;
    sinCosTurn(turns - std::floor(turns), &s, &co);
    sinCosTurn(step_turns - std::floor(step_turns), &ds, &dc);
    for (int k = 0; k < n; ++k)
    {
      sums[k].add(x, s, co);
      const double s_next = s * dc + co * ds;
      co = co * dc - s * ds;
      s = s_next;
    }
  }
  amplitude->resize(n);
  phase->resize(n);
  for (int k = 0; k < n; ++k)
  {
    sums[k].solve(&(*amplitude)[k], &(*phase)[k]);
  }
}

/// Frequency near f0 (within +-df) that maximises the least-squares sinusoid amplitude of the
/// real recording minus the mean of the ensemble's (a motion common to the runs cancels). The
/// fit is linear in the data: runs of equal length on equal stamps are averaged first, so each
/// trial frequency costs two fits instead of one per run.
double refineFrequency(const Recording& r, const std::vector<Recording>* sims, int c, double f0, double df, double t0,
                       double* amplitude, double* phase)
{
  std::vector<const Recording*> ens;
  Recording mean_run;
  if (sims != nullptr && !sims->empty())
  {
    bool same = true;
    for (const auto& sr : *sims)
    {
      same = same && sr.size() == sims->front().size() && sr.stamp == sims->front().stamp;
    }
    if (same)
    {
      mean_run.stamp = sims->front().stamp;
      mean_run.data = Eigen::MatrixXd::Zero(sims->front().size(), kChannels);
      for (const auto& sr : *sims)
      {
        mean_run.data.col(c) += sr.data.col(c) / static_cast<double>(sims->size());
      }
      ens.push_back(&mean_run);
    }
    else
    {
      for (const auto& sr : *sims)
      {
        ens.push_back(&sr);
      }
    }
  }
  // Trial frequencies f0 + df k / 20 for k = -20 .. 20 (those above 0).
  constexpr int kHalf = 20;
  const double step = df / kHalf;
  std::vector<double> a, p;
  sinusoidFitGrid(r, c, f0 - kHalf * step, step, 2 * kHalf + 1, t0, &a, &p);
  std::vector<double> sa(a.size(), 0.0), sb(a.size(), 0.0);
  for (const Recording* sr : ens)
  {
    std::vector<double> aj, pj;
    sinusoidFitGrid(*sr, c, f0 - kHalf * step, step, 2 * kHalf + 1, t0, &aj, &pj);
    for (std::size_t k = 0; k < a.size(); ++k)
    {
      sa[k] += aj[k] * std::cos(pj[k]) / ens.size();
      sb[k] += aj[k] * std::sin(pj[k]) / ens.size();
    }
  }
  double best_f = f0, best_a = -1, best_p = 0;
  for (int k = -kHalf; k <= kHalf; ++k)
  {
    const double f = f0 + df * k / kHalf;
    if (f <= 0)
    {
      continue;
    }
    double ak = a[k + kHalf], pk = p[k + kHalf];
    if (!ens.empty())
    {
      const double ra = ak * std::cos(pk) - sa[k + kHalf], rb = ak * std::sin(pk) - sb[k + kHalf];
      ak = std::hypot(ra, rb);
      pk = std::atan2(rb, ra);
    }
    if (ak > best_a)
    {
      best_a = ak;
      best_f = f;
      best_p = pk;
    }
  }
  *amplitude = std::max(0.0, best_a);
  *phase = best_p;
  return best_f;
}

Candidate make(const std::string& name, std::vector<sim::EffectSpec> specs, const std::string& note)
{
  Candidate c;
  c.effect = name;
  c.specs = std::move(specs);
  c.note = note;
  if (!c.specs.empty())
  {
    c.params = paramsJson(c.specs.back());
  }
  return c;
}

/// Allan variance of the recording against the ensemble, per channel: at the sample taus shorter
/// than a block, then at the long taus of 32 block means of (recording - ensemble mean of the
/// other runs), which takes a motion common to the runs out of the long-tau Allan variance.
struct AllanExcess
{
  std::vector<Vec> tau;     ///< [s]
  std::vector<Vec> excess;  ///< real minus ensemble Allan variance
  std::vector<Vec> null;    ///< the ensemble's own Allan variance (at least 1e-300)
  std::vector<Vec> spread;  ///< its standard deviation over the runs

  /// Excess beyond 4 spreads and 5 % of the ensemble's own variance.
  bool significant(int c, std::size_t k) const
  {
    return excess[c][k] > 4.0 * spread[c][k] && excess[c][k] > 0.05 * null[c][k];
  }
};

/// The strongest excess spectral line per channel and the ensemble's mean fine PSD.
struct LineSearch
{
  std::vector<Line> lines;       ///< per channel (power 0: none)
  std::vector<Line> fast_lines;  ///< per channel, from kVibrationMinFrequency up
  std::vector<Vec> mean_psd;     ///< per channel, ensemble mean of the fine PSD
};

/// What the fitters share, built once: the statistics of the recording and of every run.
struct FitContext
{
  const Recording& real;
  const std::vector<Recording>& runs;
  const sim::Scenario& scenario;
  double rate;
  std::size_t samples;  ///< the shortest of the recording and the runs
  bool temperature;     ///< the scenario and the recording have a temperature
  double start;         ///< the recording's stamp at elapsed 0 of the matched scenario
  FitStats real_stats;
  std::vector<FitStats> run_stats;
  std::optional<AllanExcess> allan;  ///< none when the recording is too short for one tau
  LineSearch line_search;
  /// Parameters of the fitter running now that its search range stopped (bounded()).
  mutable std::vector<std::string> at_limit;

  /// v clamped to [lo, hi]. An element beyond a bound other than 0 is noted in at_limit: the
  /// search range, not the data, decided it. (A density or amplitude estimated below 0 means
  /// none, not a limit.)
  Vec bounded(const std::string& name, Vec v, double lo, double hi) const
  {
    for (std::size_t i = 0; i < v.size(); ++i)
    {
      const double bound = v[i] < lo ? lo : v[i] > hi ? hi : v[i];
      if (bound != v[i] && bound != 0.0)
      {
        std::ostringstream note;
        note << name << (v.size() > 1 ? "[" + std::to_string(i) + "]" : "") << " = " << v[i]
             << ", held at its search limit " << bound;
        at_limit.push_back(note.str());
      }
      v[i] = bound;
    }
    return v;
  }

  /// A statistic of the recording against the ensemble's mean and spread.
  template <typename F>
  Cmp measure(F statistic) const
  {
    Vec v;
    for (const auto& s : run_stats)
    {
      v.push_back(statistic(s));
    }
    return { statistic(real_stats), meanOf(v), stdOf(v) };
  }
};

/// Blocks of the long-tau Allan variance.
constexpr int kAllanBlocks = 32;

/// kAllanBlocks block means of every channel of a recording, each of block_length samples.
Eigen::MatrixXd blockMeans(const Recording& r, std::size_t block_length)
{
  Eigen::MatrixXd means(kAllanBlocks, kChannels);
  for (int k = 0; k < kAllanBlocks; ++k)
  {
    means.row(k) = r.data.middleRows(k * block_length, block_length).colwise().mean();
  }
  return means;
}

AllanExcess allanExcess(const FitContext& context, const std::vector<int>& allan_m)
{
  const std::size_t block_length = context.samples / kAllanBlocks;
  const double block_seconds = block_length / context.rate;
  const int runs = static_cast<int>(context.runs.size());
  std::vector<Eigen::MatrixXd> run_blocks(runs);
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(kAllanBlocks, kChannels);
  for (int j = 0; j < runs; ++j)
  {
    run_blocks[j] = blockMeans(context.runs[j], block_length);
    sum += run_blocks[j];
  }
  const Eigen::MatrixXd real_blocks = blockMeans(context.real, block_length) - sum / runs;
  const std::vector<int> block_m = { 1, 2, 4, 8 };
  AllanExcess out;
  out.tau.resize(kChannels);
  out.excess.resize(kChannels);
  out.null.resize(kChannels);
  out.spread.resize(kChannels);
  for (int c = 0; c < kChannels; ++c)
  {
    for (std::size_t k = 0; k < allan_m.size(); ++k)
    {
      const double t = allan_m[k] / context.rate;
      if (t >= block_seconds)
      {
        break;
      }
      const Cmp m = context.measure([c, k](const FitStats& st) { return st.avar[c][k]; });
      out.tau[c].push_back(t);
      out.excess[c].push_back(m.real - m.sim);
      out.null[c].push_back(std::max(m.sim, 1e-300));
      out.spread[c].push_back(m.spread);
    }
    const Eigen::VectorXd real_column = real_blocks.col(c);
    const Vec real_adev = allanDeviation(real_column, block_m);
    std::vector<Vec> run_avar(block_m.size());
    for (int j = 0; j < runs; ++j)
    {
      const Eigen::VectorXd dj = run_blocks[j].col(c) - (sum.col(c) - run_blocks[j].col(c)) / std::max(1, runs - 1);
      const Vec a = allanDeviation(dj, block_m);
      for (std::size_t k = 0; k < block_m.size(); ++k)
      {
        run_avar[k].push_back(std::isfinite(a[k]) ? a[k] * a[k] : 0.0);
      }
    }
    for (std::size_t k = 0; k < block_m.size(); ++k)
    {
      if (!std::isfinite(real_adev[k]))
      {
        continue;
      }
      // (runs - 1) / runs: a leave-one-out residual carries more of the others' noise than the real one
      const double null = meanOf(run_avar[k]) * (runs - 1.0) / runs;
      out.tau[c].push_back(block_m[k] * block_seconds);
      out.excess[c].push_back(real_adev[k] * real_adev[k] - null);
      out.null[c].push_back(std::max(null, 1e-300));
      out.spread[c].push_back(stdOf(run_avar[k]));
    }
  }
  return out;
}

LineSearch lineSearch(const FitContext& context)
{
  LineSearch out;
  out.lines.resize(kChannels);
  out.fast_lines.resize(kChannels);
  out.mean_psd.resize(kChannels);
  for (int c = 0; c < kChannels; ++c)
  {
    out.mean_psd[c] = meanPsd(context.run_stats, c);
    // The ensemble's own line spread: require a clear excess over its largest member.
    Vec max_psd = out.mean_psd[c];
    for (const auto& s : context.run_stats)
    {
      for (std::size_t k = 0; k < max_psd.size(); ++k)
      {
        max_psd[k] = std::max(max_psd[k], s.psd_fine[c].power[k]);
      }
    }
    const auto search = [&](double min_freq) {
      const Line line = strongestLine(context.real_stats.psd_fine[c], max_psd, 6.0, min_freq);
      return line.power > 0 ? strongestLine(context.real_stats.psd_fine[c], out.mean_psd[c], 6.0, min_freq) : line;
    };
    out.lines[c] = search(0.0);
    out.fast_lines[c] = search(kVibrationMinFrequency);
  }
  return out;
}

/// One fitted effect: what it puts in the scenario and how it was fitted.
struct Fit
{
  std::vector<sim::EffectSpec> specs;
  std::string note;
};

/// Adds the scenario's own values of an additive effect's accel and gyro parameters (summed over
/// its occurrences) to the fitted differences.
void addPresent(const std::vector<sim::EffectSpec>& present, const std::string& accel_key, const std::string& gyro_key,
                Vec* acc, Vec* gyr)
{
  const Vec a0 = sumParam(present, accel_key, acc->size()), g0 = sumParam(present, gyro_key, gyr->size());
  for (std::size_t i = 0; i < acc->size(); ++i)
  {
    (*acc)[i] += a0[i];
    (*gyr)[i] += g0[i];
  }
}

/// Real minus ensemble of a per-channel statistic on the channels where it departs by more than
/// 4 spreads plus a floor (accel_floor on the accelerometer, gyro_floor on the gyro); the other
/// channels are left as they are. True if any channel departs.
template <typename F>
bool channelShifts(const FitContext& context, F statistic, double accel_floor, double gyro_floor, Vec* acc, Vec* gyr)
{
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    const Cmp m = context.measure([&statistic, c](const FitStats& s) { return statistic(s, c); });
    if (m.significant(4.0, c < 3 ? accel_floor : gyro_floor))
    {
      (c < 3 ? (*acc)[c] : (*gyr)[c - 3]) = m.real - m.sim;
      any = true;
    }
  }
  return any;
}

/// constant_bias: the difference of means per axis, beyond 4 ensemble spreads.
std::optional<Fit> fitConstantBias(const FitContext& context)
{
  Vec acc(3, 0.0), gyr(3, 0.0);
  if (!channelShifts(
          context, [](const FitStats& s, int c) { return s.mean[c]; }, 1e-5, 1e-7, &acc, &gyr))
  {
    return std::nullopt;
  }
  addPresent(existing(context.scenario, "constant_bias"), "accel", "gyro", &acc, &gyr);
  sim::EffectSpec e{ "constant_bias", true, {} };
  e.params["accel"] = context.bounded("accel", acc, -100, 100);
  e.params["gyro"] = context.bounded("gyro", gyr, -10, 10);
  return Fit{ { e }, "mean of real minus mean of the ensemble, per axis" };
}

/// white_noise: the PSD floor in the upper half of the band.
std::optional<Fit> fitWhiteNoise(const FitContext& context)
{
  Vec acc(3, 0.0), gyr(3, 0.0);
  bool any = false;
  const auto present = existing(context.scenario, "white_noise");
  const Vec a2 = sumSquares(present, "accel_density"), g2 = sumSquares(present, "gyro_density");
  for (int c = 0; c < kChannels; ++c)
  {
    auto floorOf = [c](const FitStats& s) {
      const auto& p = s.psd[c].power;
      Vec v(p.begin() + p.size() / 2, p.end() - p.size() / 20);
      return medianOf(v);
    };
    const Cmp m = context.measure(floorOf);
    const double base = c < 3 ? a2[c] : g2[c - 3];
    double d2 = base + (m.real - m.sim) / 2.0;
    if (m.significant(4.0) && std::abs(m.real - m.sim) > 0.1 * m.sim)
    {
      any = true;
    }
    d2 = std::max(0.0, d2);
    (c < 3 ? acc[c] : gyr[c - 3]) = std::sqrt(d2);
  }
  if (!any)
  {
    return std::nullopt;
  }
  sim::EffectSpec e{ "white_noise", true, {} };
  e.params["accel_density"] = context.bounded("accel_density", acc, 0, 10);
  e.params["gyro_density"] = context.bounded("gyro_density", gyr, 0, 10);
  return Fit{ { e }, "PSD floor (upper half band): density^2 += (P_real - P_sim) / 2" };
}

/// bias_random_walk: the Allan variance excess at the 3 longest taus.
std::optional<Fit> fitBiasRandomWalk(const FitContext& context)
{
  if (!context.allan)
  {
    return std::nullopt;
  }
  const AllanExcess& allan = *context.allan;
  Vec acc(3, 0.0), gyr(3, 0.0);
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    Vec k2;
    bool sig = false;
    const std::size_t nt = allan.tau[c].size();
    for (std::size_t k = nt >= 3 ? nt - 3 : 0; k < nt; ++k)
    {
      if (allan.excess[c][k] > 0)
      {
        k2.push_back(3.0 * allan.excess[c][k] / allan.tau[c][k]);
      }
      sig = sig || allan.significant(c, k);
    }
    if (sig && !k2.empty())
    {
      (c < 3 ? acc[c] : gyr[c - 3]) = std::sqrt(medianOf(k2));
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  const auto present = existing(context.scenario, "bias_random_walk");
  const Vec a2 = sumSquares(present, "accel_density"), g2 = sumSquares(present, "gyro_density");
  for (int i = 0; i < 3; ++i)
  {
    acc[i] = std::sqrt(acc[i] * acc[i] + a2[i]);
    gyr[i] = std::sqrt(gyr[i] * gyr[i] + g2[i]);
  }
  sim::EffectSpec e{ "bias_random_walk", true, {} };
  e.params["accel_density"] = context.bounded("accel_density", acc, 0, 10);
  e.params["gyro_density"] = context.bounded("gyro_density", gyr, 0, 10);
  return Fit{ { e }, "Allan variance excess at the 3 longest taus = K^2 tau / 3" };
}

/// Weighted least-squares sigma^2 of a Gauss-Markov Allan curve with correlation time tc on a
/// channel's Allan excess; adds the weighted squared residuals to *cost.
double gaussMarkovVariance(const AllanExcess& allan, int c, double tc, double* cost)
{
  double num = 0, den = 0;
  for (std::size_t k = 0; k < allan.tau[c].size(); ++k)
  {
    const double g = gaussMarkovAllanVariance(allan.tau[c][k], tc);
    const double w = 1.0 / (allan.null[c][k] + std::max(allan.excess[c][k], 0.0));
    num += allan.excess[c][k] * g * w * w;
    den += g * g * w * w;
  }
  const double s2 = den > 0 ? std::max(0.0, num / den) : 0.0;
  for (std::size_t k = 0; k < allan.tau[c].size(); ++k)
  {
    const double g = gaussMarkovAllanVariance(allan.tau[c][k], tc);
    const double w = 1.0 / (allan.null[c][k] + std::max(allan.excess[c][k], 0.0));
    *cost += std::pow((allan.excess[c][k] - s2 * g) * w, 2);
  }
  return s2;
}

/// bias_instability: a grid over correlation times, sigma^2 by weighted least squares.
std::optional<Fit> fitBiasInstability(const FitContext& context)
{
  if (!context.allan)
  {
    return std::nullopt;
  }
  const AllanExcess& allan = *context.allan;
  std::vector<bool> sig(kChannels, false);
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    for (std::size_t k = 0; k < allan.tau[c].size(); ++k)
    {
      if (allan.significant(c, k))
      {
        sig[c] = true;
      }
    }
    any = any || sig[c];
  }
  if (!any)
  {
    return std::nullopt;
  }
  double best_cost = std::numeric_limits<double>::infinity();
  double best_tc = 0;
  Vec best_sigma(kChannels, 0.0);
  const double span = context.samples / context.rate;
  for (double tc = 2.0 / context.rate; tc <= 2.0 * span; tc *= std::sqrt(2.0))
  {
    double cost = 0.0;
    Vec sigma(kChannels, 0.0);
    for (int c = 0; c < kChannels; ++c)
    {
      if (sig[c])
      {
        sigma[c] = std::sqrt(gaussMarkovVariance(allan, c, tc, &cost));
      }
    }
    if (cost < best_cost)
    {
      best_cost = cost;
      best_tc = tc;
      best_sigma = sigma;
    }
  }
  if (!(best_tc > 0 && anyNonZero(best_sigma)))
  {
    return std::nullopt;
  }
  std::vector<sim::EffectSpec> specs = existing(context.scenario, "bias_instability");
  sim::EffectSpec e{ "bias_instability", true, {} };
  e.params["accel_sigma"] = context.bounded("accel_sigma", Vec(best_sigma.begin(), best_sigma.begin() + 3), 0, 100);
  e.params["gyro_sigma"] = context.bounded("gyro_sigma", Vec(best_sigma.begin() + 3, best_sigma.end()), 0, 10);
  e.params["correlation_time"] = { std::max(1e-3, best_tc) };
  if (best_tc < 3.0 / context.rate || best_tc * std::sqrt(2.0) > 2.0 * span)
  {
    std::ostringstream note;
    note << "correlation_time = " << best_tc << ", an end of its search grid (2 samples to twice the span)";
    context.at_limit.push_back(note.str());
  }
  specs.push_back(e);
  return Fit{ specs, "Allan variance excess fitted by a Gauss-Markov curve (grid over correlation time)" };
}

/// scale_factor: the motion-band power ratio; on an axis carrying gravity, the ratio of means.
std::optional<Fit> fitScaleFactor(const FitContext& context)
{
  Vec acc(3, 0.0), gyr(3, 0.0);
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    const Cmp mm = context.measure([c](const FitStats& s) { return s.mean[c]; });
    if (c < 3 && std::abs(mm.sim) > 1.0)
    {
      // an axis carrying gravity: its mean scales (indistinguishable from a bias on this axis)
      if (mm.significant(4.0, 1e-5))
      {
        acc[c] = mm.real / mm.sim - 1.0;
        any = true;
      }
      continue;
    }
    const auto bins = motionBins(context.run_stats, c);
    if (bins.size() < 2)
    {
      continue;
    }
    auto power = [&bins, c](const FitStats& s) {
      double p = 0.0;
      for (std::size_t k : bins)
      {
        p += s.psd[c].power[k];
      }
      return std::sqrt(p);
    };
    const Cmp m = context.measure(power);
    if (m.sim > 0 && m.significant(4.0) && std::abs(m.real / m.sim - 1.0) > 0.002)
    {
      (c < 3 ? acc[c] : gyr[c - 3]) = m.real / m.sim - 1.0;
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  const auto present = existing(context.scenario, "scale_factor");
  Vec a0(3, 1.0), g0(3, 1.0);
  for (const auto& e : present)
  {
    for (int i = 0; i < 3; ++i)
    {
      a0[i] *= 1.0 + e.params.at("accel")[i];
      g0[i] *= 1.0 + e.params.at("gyro")[i];
    }
  }
  for (int i = 0; i < 3; ++i)
  {
    acc[i] = a0[i] * (1.0 + acc[i]) - 1.0;
    gyr[i] = g0[i] * (1.0 + gyr[i]) - 1.0;
  }
  sim::EffectSpec e{ "scale_factor", true, {} };
  e.params["accel"] = context.bounded("accel", acc, -0.5, 0.5);
  e.params["gyro"] = context.bounded("gyro", gyr, -0.5, 0.5);
  return Fit{ { e }, "sqrt of motion-band power ratio real / ensemble" };
}

/// The accelerometer axis carrying gravity in the ensemble (the largest mean above 1 m/s^2), -1
/// if none.
int gravityAxis(const std::vector<FitStats>& ensemble)
{
  int axis = -1;
  for (int j = 0; j < 3; ++j)
  {
    Vec means;
    for (const auto& st : ensemble)
    {
      means.push_back(st.mean[j]);
    }
    if (std::abs(meanOf(means)) > 1.0 && (axis < 0 || std::abs(ensemble[0].mean[j]) > std::abs(ensemble[0].mean[axis])))
    {
      axis = j;
    }
  }
  return axis;
}

/// Misalignment onto the gravity axis j: the mean of each other accelerometer axis i moves by
/// M_ij g. Writes accel[3 i + j]; true if any is significant.
bool gravityCoupling(const FitContext& context, int j, Vec* accel)
{
  bool any = false;
  for (int i = 0; i < 3; ++i)
  {
    if (i == j)
    {
      continue;
    }
    const Cmp mi = context.measure([i](const FitStats& st) { return st.mean[i]; });
    const Cmp mj = context.measure([j](const FitStats& st) { return st.mean[j]; });
    if (mi.significant(4.0, 1e-5))
    {
      (*accel)[3 * i + j] = (mi.real - mi.sim) / mj.sim;
      any = true;
    }
  }
  return any;
}

/// Misalignment of sensor s (0 accel, 1 gyro) from axis j onto each other axis i: the
/// cross-spectrum excess over the auto-spectrum, in the bins of j's motion band where j's motion
/// dominates i's own (ensemble mean), so that i's motion does not leak into the estimate.
/// Writes coupling[3 i + j]; true if any is significant.
bool motionCoupling(const FitContext& context, int s, int j, Vec* coupling_out)
{
  const auto bins = motionBins(context.run_stats, 3 * s + j);
  if (bins.size() < 2)
  {
    return false;
  }
  bool any = false;
  for (int i = 0; i < 3; ++i)
  {
    if (i == j)
    {
      continue;
    }
    std::vector<std::size_t> own;
    for (std::size_t k : bins)
    {
      double pjj = 0, pii = 0;
      for (const auto& st : context.run_stats)
      {
        pjj += st.cross[s][k](j, j);
        pii += st.cross[s][k](i, i);
      }
      if (pjj > 10.0 * pii)
      {
        own.push_back(k);
      }
    }
    if (own.empty())
    {
      continue;
    }
    auto coupling = [&own, s, i, j](const FitStats& st) {
      double num = 0, den = 0;
      for (std::size_t k : own)
      {
        num += st.cross[s][k](i, j);
        den += st.cross[s][k](j, j);
      }
      return den > 0 ? num / den : 0.0;
    };
    const Cmp m = context.measure(coupling);
    if (m.significant(4.0, 1e-4))
    {
      (*coupling_out)[3 * i + j] = m.real - m.sim;
      any = true;
    }
  }
  return any;
}

/// misalignment: the cross-spectral excess in each axis's motion band; onto the gravity axis,
/// the mean shift / g.
std::optional<Fit> fitMisalignment(const FitContext& context)
{
  Vec acc(9, 0.0), gyr(9, 0.0);
  bool any = false;
  const int gravity = gravityAxis(context.run_stats);
  for (int s = 0; s < 2; ++s)
  {
    for (int j = 0; j < 3; ++j)
    {
      const bool found = s == 0 && j == gravity ? gravityCoupling(context, j, &acc)
                                                : motionCoupling(context, s, j, s == 0 ? &acc : &gyr);
      any = any || found;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  addPresent(existing(context.scenario, "misalignment"), "accel", "gyro", &acc, &gyr);
  sim::EffectSpec e{ "misalignment", true, {} };
  e.params["accel"] = context.bounded("accel", acc, -0.5, 0.5);
  e.params["gyro"] = context.bounded("gyro", gyr, -0.5, 0.5);
  return Fit{ { e }, "cross-spectrum excess / auto-spectrum in the motion band of each axis" };
}

/// lever_arm: the regression of accel on alpha x r + omega x (omega x r), real minus ensemble.
std::optional<Fit> fitLeverArm(const FitContext& context)
{
  const FitStats& real = context.real_stats;
  if (!real.lever_ok)
  {
    return std::nullopt;
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  int count = 0;
  for (const auto& s : context.run_stats)
  {
    if (s.lever_ok)
    {
      mean += s.lever;
      sq += s.lever.cwiseProduct(s.lever);
      ++count;
    }
  }
  if (count < 2)
  {
    return std::nullopt;
  }
  mean /= count;
  const Eigen::Vector3d sd =
      (sq / count - mean.cwiseProduct(mean)).cwiseMax(0.0).cwiseSqrt() * std::sqrt(count / (count - 1.0));
  Vec d(3, 0.0);
  bool any = false;
  for (int i = 0; i < 3; ++i)
  {
    if (std::abs(real.lever[i] - mean[i]) > 4.0 * sd[i] + 0.01)
    {
      d[i] = real.lever[i] - mean[i];
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  const Vec r0 = sumParam(existing(context.scenario, "lever_arm"), "offset", 3);
  for (int i = 0; i < 3; ++i)
  {
    d[i] += r0[i];
  }
  sim::EffectSpec e{ "lever_arm", true, {} };
  e.params["offset"] = context.bounded("offset", d, -100, 100);
  return Fit{ { e },
              "least squares of accel on alpha x r + omega x (omega x r) (omega from the gyro), real minus ensemble" };
}

/// periodic_bias: the strongest excess line per axis, frequency refined by least squares.
/// A line too slow for the spectrum (under about 2.5 cycles in the fit part) on channel c: the
/// sinusoid that best fits the block means of the recording minus the ensemble's mean, over 96
/// periods on a log grid from 0.4 of the span to 4 spans, the best refined by a parabola through
/// its neighbours' residuals. Kept when the block means depart by 4 times the ensemble's own
/// spread of a block mean (RMS), and the sinusoid removes 80 % of their variance.
bool slowLine(const FitContext& context, int c, double* amplitude, double* period, double* phase)
{
  const std::size_t block_length = context.samples / kAllanBlocks;
  if (block_length < 1 || context.runs.size() < 2)
  {
    return false;
  }
  Eigen::VectorXd ensemble = Eigen::VectorXd::Zero(kAllanBlocks);
  std::vector<Eigen::VectorXd> runs;
  for (const Recording& run : context.runs)
  {
    runs.push_back(blockMeans(run, block_length).col(c));
    ensemble += runs.back() / static_cast<double>(context.runs.size());
  }
  double spread2 = 0.0;
  for (const Eigen::VectorXd& run : runs)
  {
    spread2 += (run - ensemble).squaredNorm() / (kAllanBlocks * (runs.size() - 1.0));
  }
  const Eigen::VectorXd y = blockMeans(context.real, block_length).col(c) - ensemble;
  const double variance = (y.array() - y.mean()).square().sum();
  if (!(variance > 16.0 * spread2 * kAllanBlocks))
  {
    return false;
  }
  Eigen::VectorXd t(kAllanBlocks);
  for (int k = 0; k < kAllanBlocks; ++k)
  {
    t[k] = context.real.stamp[static_cast<std::size_t>((k + 0.5) * block_length)] - context.start;
  }
  // Offset, sine and cosine fitted at period p: the residual, and amplitude and phase of
  // A sin(2 pi t / p + phase).
  const auto fit = [&](double p, double* a, double* ph) {
    Eigen::MatrixXd m(kAllanBlocks, 3);
    m.col(0).setOnes();
    m.col(1) = (2.0 * M_PI / p * t).array().sin();
    m.col(2) = (2.0 * M_PI / p * t).array().cos();
    const Eigen::Vector3d x = m.colPivHouseholderQr().solve(y);
    *a = std::hypot(x[1], x[2]);
    *ph = std::atan2(x[2], x[1]);
    return (y - m * x).squaredNorm();
  };
  constexpr int kPeriods = 96;
  const double span = kAllanBlocks * block_length / context.rate;
  const auto grid = [span](double i) { return 0.4 * span * std::pow(10.0, i / (kPeriods - 1)); };
  std::vector<double> residual(kPeriods);
  double a = 0.0, ph = 0.0;
  int best = 0;
  for (int i = 0; i < kPeriods; ++i)
  {
    residual[i] = fit(grid(i), &a, &ph);
    best = residual[i] < residual[best] ? i : best;
  }
  double at = best;
  if (best > 0 && best + 1 < kPeriods)
  {
    const double curvature = residual[best - 1] - 2.0 * residual[best] + residual[best + 1];
    at += curvature > 0.0 ? std::clamp(0.5 * (residual[best - 1] - residual[best + 1]) / curvature, -0.5, 0.5) : 0.0;
  }
  *period = grid(at);
  return fit(*period, amplitude, phase) < 0.2 * variance;
}

std::optional<Fit> fitPeriodicBias(const FitContext& context)
{
  const std::vector<Line>& lines = context.line_search.lines;
  Vec amp(6, 0.0), per(6, 10.0), ph(6, 0.0);
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    const double span = context.samples / context.rate;
    const bool slow = !(lines[c].power > 0 && lines[c].freq > 0) || lines[c].freq * span < 2.5;
    if (slow && slowLine(context, c, &amp[c], &per[c], &ph[c]))
    {
      any = true;
    }
    else if (lines[c].power > 0 && lines[c].freq > 0)
    {
      double a = 0, p = 0;
      const double f = refineFrequency(context.real, &context.runs, c, lines[c].freq, context.real_stats.psd_fine[c].df,
                                       context.start, &a, &p);
      amp[c] = std::min(a, std::sqrt(2.0 * lines[c].power) * 1.5);
      per[c] = 1.0 / f;
      ph[c] = p;
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  std::vector<sim::EffectSpec> specs = existing(context.scenario, "periodic_bias");
  sim::EffectSpec e{ "periodic_bias", true, {} };
  e.params["accel_amplitude"] = context.bounded("accel_amplitude", Vec(amp.begin(), amp.begin() + 3), 0, 100);
  e.params["gyro_amplitude"] = context.bounded("gyro_amplitude", Vec(amp.begin() + 3, amp.end()), 0, 10);
  e.params["accel_period"] = context.bounded("accel_period", Vec(per.begin(), per.begin() + 3), 1e-3, 1e7);
  e.params["gyro_period"] = context.bounded("gyro_period", Vec(per.begin() + 3, per.end()), 1e-3, 1e7);
  e.params["accel_phase"] = Vec(ph.begin(), ph.begin() + 3);
  e.params["gyro_phase"] = Vec(ph.begin() + 3, ph.end());
  specs.push_back(e);
  return Fit{ specs,
              "strongest excess spectral line per axis: amplitude sqrt(2 P), period 1 / f; a line too slow "
              "for the spectrum from the block means" };
}

/// Signed amplitude of a line at frequency f (PSD bin k0, width_bins wide) on every channel where
/// it shows (6 x the ensemble's mean PSD), the sign from the phase against ref_phase.
Vec lineAmplitudes(const FitContext& context, double f, std::size_t k0, double width_bins, double ref_phase)
{
  Vec amp(6, 0.0);
  for (int c = 0; c < kChannels; ++c)
  {
    const Psd& psd = context.real_stats.psd_fine[c];
    const Vec& ensemble_psd = context.line_search.mean_psd[c];
    const auto& p = psd.power;
    double pw = 0.0;
    bool shows = false;
    const std::size_t half = static_cast<std::size_t>(std::max(2.0, width_bins / 2 + 1));
    for (std::size_t k = k0 > half ? k0 - half : 1; k <= std::min(p.size() - 1, k0 + half); ++k)
    {
      pw += std::max(0.0, p[k] - ensemble_psd[k]) * psd.df;
      shows = shows || p[k] > 6.0 * ensemble_psd[k];
    }
    if (shows)
    {
      double a_c = 0, ph_c = 0;
      sinusoidFit(context.real, c, f, context.start, &a_c, &ph_c);
      const double sign = std::cos(ph_c - ref_phase) >= 0 ? 1.0 : -1.0;
      amp[c] = sign * std::min(a_c, 1.5 * std::sqrt(2.0 * pw));
    }
  }
  return amp;
}

/// vibration: the line with the largest excess ratio, on every axis where it shows.
std::optional<Fit> fitVibration(const FitContext& context)
{
  const std::vector<Line>& lines = context.line_search.fast_lines;
  int best = -1;
  for (int c = 0; c < kChannels; ++c)
  {
    if (lines[c].power > 0 && (best < 0 || lines[c].ratio > lines[best].ratio))
    {
      best = c;
    }
  }
  if (best < 0)
  {
    return std::nullopt;
  }
  const Line& line = lines[best];
  const double df = context.real_stats.psd_fine[best].df;
  double a_ref = 0, ph_ref = 0;
  const double f = refineFrequency(context.real, &context.runs, best, line.freq, df, context.start, &a_ref, &ph_ref);
  const Vec amp = lineAmplitudes(context, f, line.bin, line.width_bins, ph_ref);
  double a = 0, phase = 0;
  sinusoidFit(context.real, best, f, context.start, &a, &phase);
  double bw = 0.0;
  if (line.width_bins > 6)
  {
    bw = (line.width_bins - 4) * df / 2.0;
  }
  std::vector<sim::EffectSpec> specs = existing(context.scenario, "vibration");
  sim::EffectSpec e{ "vibration", true, {} };
  e.params["frequency"] = { f };
  e.params["accel_amplitude"] = context.bounded("accel_amplitude", Vec(amp.begin(), amp.begin() + 3), -100, 100);
  e.params["gyro_amplitude"] = context.bounded("gyro_amplitude", Vec(amp.begin() + 3, amp.end()), -10, 10);
  e.params["phase"] = { phase };
  e.params["bandwidth"] = { bw };
  specs.push_back(e);
  return Fit{ specs, "strongest excess line above 1 Hz over all axes, amplitude per axis sqrt(2 P)" };
}

/// thermal_drift: the slope of block means against temperature, real minus ensemble.
std::optional<Fit> fitThermalDrift(const FitContext& context)
{
  if (!context.temperature)
  {
    return std::nullopt;
  }
  Vec acc(3, 0.0), gyr(3, 0.0);
  if (!channelShifts(
          context, [](const FitStats& s, int c) { return s.temp_slope[c]; }, 1e-6, 1e-8, &acc, &gyr))
  {
    return std::nullopt;
  }
  const auto present = existing(context.scenario, "thermal_drift");
  addPresent(present, "accel_coefficient", "gyro_coefficient", &acc, &gyr);
  double ref = present.empty() ? 20.0 : present.front().params.at("reference_temperature")[0];
  if (present.empty())
  {
    ref = context.scenario.temperature.mean;  // no information on the reference: no constant part
  }
  sim::EffectSpec e{ "thermal_drift", true, {} };
  e.params["accel_coefficient"] = context.bounded("accel_coefficient", acc, -1, 1);
  e.params["gyro_coefficient"] = context.bounded("gyro_coefficient", gyr, -1, 1);
  e.params["reference_temperature"] = { ref };
  return Fit{ { e }, "slope of 32 block means against temperature, real minus ensemble" };
}

/// sample_hold: readings repeated more often than in the ensemble.
std::optional<Fit> fitSampleHold(const FitContext& context)
{
  const Cmp m = context.measure([](const FitStats& s) { return s.repeated; });
  if (!(m.real > 0.02 && m.real > 2.0 * m.sim + 0.01))
  {
    return std::nullopt;
  }
  sim::EffectSpec e{ "sample_hold", true, {} };
  e.params["sensor_rate"] = { context.rate * (1.0 - m.real) };
  return Fit{ { e }, "rows repeating their predecessor: sensor rate = rate x (1 - fraction)" };
}

/// saturation: flat tops the ensemble does not have.
std::optional<Fit> fitSaturation(const FitContext& context)
{
  const FitStats& real = context.real_stats;
  const auto present = existing(context.scenario, "saturation");
  Vec lim(6, 0.0);
  for (int c = 0; c < kChannels; ++c)
  {
    lim[c] = c < 3 ? 160.0 : 35.0;
    for (const auto& e : present)
    {
      lim[c] = std::min(lim[c], e.params.at(c < 3 ? "accel_limit" : "gyro_limit")[c % 3]);
    }
  }
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    const Cmp m = context.measure([c](const FitStats& s) { return s.flat[c]; });
    if (real.flat[c] > 0 && real.limit[c] < lim[c] * 0.999 && m.real > 2.0 * m.sim + 1e-5)
    {
      lim[c] = real.limit[c];
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  sim::EffectSpec e{ "saturation", true, {} };
  e.params["accel_limit"] = Vec(lim.begin(), lim.begin() + 3);
  e.params["gyro_limit"] = Vec(lim.begin() + 3, lim.end());
  return Fit{ { e }, "flat tops: limit = largest magnitude, seen repeatedly" };
}

/// quantization: a lattice the ensemble does not have.
std::optional<Fit> fitQuantization(const FitContext& context)
{
  const FitStats& real = context.real_stats;
  const auto present = existing(context.scenario, "quantization");
  Vec step = present.empty() ? Vec(6, 0.0) : Vec{};
  if (!present.empty())
  {
    const Vec& a = present.back().params.at("accel_step");
    const Vec& g = present.back().params.at("gyro_step");
    step = { a[0], a[1], a[2], g[0], g[1], g[2] };
  }
  bool any = false;
  for (int c = 0; c < kChannels; ++c)
  {
    double sim_step = 0.0;
    for (const auto& s : context.run_stats)
    {
      sim_step = std::max(sim_step, s.lattice[c]);
    }
    if (real.lattice[c] > 0 && std::abs(real.lattice[c] - sim_step) > 1e-3 * real.lattice[c])
    {
      step[c] = real.lattice[c];
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  sim::EffectSpec e{ "quantization", true, {} };
  e.params["accel_step"] = context.bounded("accel_step", Vec(step.begin(), step.begin() + 3), 0, 100);
  e.params["gyro_step"] = context.bounded("gyro_step", Vec(step.begin() + 3, step.end()), 0, 10);
  return Fit{ { e }, "values on a lattice: step = smallest gap between distinct values" };
}

/// gravity_leakage: the horizontal specific force in the REPORTED frame, real minus ensemble.
std::optional<Fit> fitGravityLeakage(const FitContext& context)
{
  const FitStats& real = context.real_stats;
  if (!(real.has_leak && context.run_stats[0].has_leak))
  {
    return std::nullopt;
  }
  const Cmp east = context.measure([](const FitStats& s) { return s.leak_e; });
  const Cmp north = context.measure([](const FitStats& s) { return s.leak_n; });
  const Cmp yaw = context.measure([](const FitStats& s) { return s.yaw; });
  const bool sig_tilt = east.significant(4.0, 2e-4) || north.significant(4.0, 2e-4);
  const double dyaw = wrapAngle(yaw.real - yaw.sim);
  const bool sig_yaw = std::abs(dyaw) > 4.0 * yaw.spread + 2e-4;
  if (!(sig_tilt || sig_yaw))
  {
    return std::nullopt;
  }
  const double de = east.real - east.sim, dn = north.real - north.sim;
  const double c = std::cos(real.yaw), s = std::sin(real.yaw);
  const double bx = c * de + s * dn;   // body x (forward) component of the leak
  const double by = -s * de + c * dn;  // body y (left)
  const auto present = existing(context.scenario, "gravity_leakage");
  const Vec r0 = sumParam(present, "roll", 1), p0 = sumParam(present, "pitch", 1), y0 = sumParam(present, "yaw", 1);
  sim::EffectSpec spec{ "gravity_leakage", true, {} };
  spec.params["roll"] = { std::max(-1.5, std::min(1.5, r0[0] + (sig_tilt ? -by : 0.0))) };
  spec.params["pitch"] = { std::max(-1.5, std::min(1.5, p0[0] + (sig_tilt ? bx : 0.0))) };
  spec.params["yaw"] = { std::max(-3.2, std::min(3.2, y0[0] + (sig_yaw ? dyaw : 0.0))) };
  return Fit{ { spec }, "mean specific force rotated by the reported orientation: horizontal part / g = tilt error" };
}

/// timestamp_jitter: the robust std of the stamps about a straight line in the sample index.
std::optional<Fit> fitTimestampJitter(const FitContext& context)
{
  const Cmp jitter = context.measure([](const FitStats& s) { return s.stamps.jitter; });
  if (!(jitter.real > 3.0 * jitter.sim + 4.0 * jitter.spread + 1e-7))
  {
    return std::nullopt;
  }
  const auto present = existing(context.scenario, "timestamp_jitter");
  const double off = present.empty() ? 0.0 : present.back().params.at("offset")[0];
  sim::EffectSpec e{ "timestamp_jitter", true, {} };
  e.params["sigma"] = { std::min(1.0, jitter.real) };
  e.params["offset"] = { off };
  return Fit{ { e }, "robust std of stamps about a straight line in the sample index" };
}

/// dropouts: gaps in the stamps.
std::optional<Fit> fitDropouts(const FitContext& context)
{
  const StampStats& stamps = context.real_stats.stamps;
  const Cmp lost = context.measure([](const FitStats& s) { return s.stamps.lost_fraction; });
  if (!(lost.real > 2.0 * lost.sim + 4.0 * lost.spread + 1e-4 && stamps.bursts > 0))
  {
    return std::nullopt;
  }
  const double kept = static_cast<double>(context.real.size());
  sim::EffectSpec e{ "dropouts", true, {} };
  e.params["probability"] = { std::min(1.0, stamps.bursts / kept) };
  e.params["burst_length"] = { std::max(1.0, stamps.mean_burst) };
  return Fit{ { e }, "gaps in the stamps: bursts per kept sample, mean missing per gap" };
}

/// A fitter per effect of the simulator's vocabulary, in the order of the candidates.
struct Fitter
{
  const char* effect;
  std::optional<Fit> (*fit)(const FitContext&);
};

const Fitter kFitters[] = {
  { "constant_bias", fitConstantBias },
  { "white_noise", fitWhiteNoise },
  { "bias_random_walk", fitBiasRandomWalk },
  { "bias_instability", fitBiasInstability },
  { "scale_factor", fitScaleFactor },
  { "misalignment", fitMisalignment },
  { "lever_arm", fitLeverArm },
  { "periodic_bias", fitPeriodicBias },
  { "vibration", fitVibration },
  { "thermal_drift", fitThermalDrift },
  { "sample_hold", fitSampleHold },
  { "saturation", fitSaturation },
  { "quantization", fitQuantization },
  { "gravity_leakage", fitGravityLeakage },
  { "timestamp_jitter", fitTimestampJitter },
  { "dropouts", fitDropouts },
};
}  // namespace

std::vector<Candidate> fitCandidates(const Recording& real_fit, const std::vector<Recording>& sims_fit,
                                     const sim::Scenario& scenario)
{
  std::vector<Candidate> out;
  if (sims_fit.empty() || real_fit.size() < 64)
  {
    return out;
  }
  std::size_t n = real_fit.size();
  for (const auto& s : sims_fit)
  {
    n = std::min(n, s.size());
  }
  const bool temperature = scenario.temperature.enabled && real_fit.has_temperature;
  const double start = real_fit.stamp.front();  // elapsed 0 of the matched scenario
  FitContext context{ real_fit, sims_fit, scenario, scenario.rate, n, temperature, start, {}, {}, {}, {}, {} };
  const int nseg = welchSegment(n);
  std::vector<int> allan_m;
  for (int m = 1; static_cast<std::size_t>(m) * 10 <= n; m *= 2)
  {
    allan_m.push_back(m);
  }
  context.real_stats = fitStats(real_fit, context.rate, nseg, allan_m, temperature);
  context.run_stats.resize(sims_fit.size());
  parallelFor(static_cast<int>(sims_fit.size()), 2,
              [&](int i) { context.run_stats[i] = fitStats(sims_fit[i], context.rate, nseg, allan_m, temperature); });
  if (!allan_m.empty())
  {
    context.allan = allanExcess(context, allan_m);
  }
  context.line_search = lineSearch(context);
  for (const Fitter& fitter : kFitters)
  {
    context.at_limit.clear();
    if (std::optional<Fit> fit = fitter.fit(context))
    {
      out.push_back(make(fitter.effect, std::move(fit->specs), fit->note));
      for (const std::string& limit : context.at_limit)
      {
        out.back().at_limit.push_back(std::string(fitter.effect) + "." + limit);
      }
    }
  }
  return out;
}
}  // namespace periodic_bias_compensation::gap
