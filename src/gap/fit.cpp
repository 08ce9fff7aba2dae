// Effect candidates: for each effect of the simulator's vocabulary, closed-form or moment
// estimates of its parameters from the difference between the real recording and the
// simulated ensemble of the scenario as given (first part of the recording only).
//
// Every candidate is a list of EffectSpec that REPLACES all occurrences of that effect in the
// scenario; additive effects carry the scenario's own value plus the fitted difference.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <Eigen/Dense>

#include "periodic_bias_compensation/gap/gap.h"
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

double medianOf(Vec v)
{
  if (v.empty())
  {
    return 0.0;
  }
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

std::string num(double v)
{
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string jsonList(const Vec& v)
{
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i)
  {
    s += (i ? ", " : "") + num(v[i]);
  }
  return s + "]";
}

std::string paramsJson(const sim::EffectSpec& spec)
{
  std::string s = "{";
  bool first = true;
  for (const auto& [k, v] : spec.params)
  {
    s += (first ? "\"" : ", \"") + k + "\": " + (v.size() == 1 ? num(v[0]) : jsonList(v));
    first = false;
  }
  return s + "}";
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

Vec clampVec(Vec v, double lo, double hi)
{
  for (double& a : v)
  {
    a = std::max(lo, std::min(hi, a));
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
  std::vector<Psd> psd;                       ///< per channel
  std::vector<Psd> psd_fine;                  ///< per channel, long segments (spectral lines)
  std::vector<Vec> avar;                      ///< per channel, Allan variance at allan_m
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
    const Eigen::Vector3d al = (sm.row(i + step).tail<3>() - sm.row(i - step).tail<3>()).transpose() * rate / (2.0 * step);
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

template <typename F>
Cmp compare(const FitStats& real, const std::vector<FitStats>& sims, F f)
{
  Vec v;
  for (const auto& s : sims)
  {
    v.push_back(f(s));
  }
  return { f(real), meanOf(v), stdOf(v) };
}

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

Line strongestLine(const Psd& real, const Vec& sim, double min_ratio)
{
  Line best;
  const std::size_t nb = real.power.size();
  for (std::size_t k = 2; k + 1 < nb; ++k)
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

/// Least-squares phase and amplitude of A sin(2 pi f t + phi) in a channel (t since the start).
void sinusoidFit(const Recording& r, int c, double f, double t0, double* amplitude, double* phase)
{
  double ss = 0, sc = 0, cc = 0, xs = 0, xc = 0;
  const double m = r.data.col(c).mean();
  for (std::size_t i = 0; i < r.size(); ++i)
  {
    const double th = 2.0 * M_PI * f * (r.stamp[i] - t0);
    const double s = std::sin(th), co = std::cos(th);
    ss += s * s;
    sc += s * co;
    cc += co * co;
    xs += (r.data(i, c) - m) * s;
    xc += (r.data(i, c) - m) * co;
  }
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
  double best_f = f0, best_a = -1, best_p = 0;
  for (int i = -20; i <= 20; ++i)
  {
    const double f = f0 + df * i / 20.0;
    if (f <= 0)
    {
      continue;
    }
    double a = 0, p = 0;
    sinusoidFit(r, c, f, t0, &a, &p);
    if (!ens.empty())
    {
      double sa = 0, sb = 0;
      for (const Recording* sr : ens)
      {
        double aj = 0, pj = 0;
        sinusoidFit(*sr, c, f, t0, &aj, &pj);
        sa += aj * std::cos(pj) / ens.size();
        sb += aj * std::sin(pj) / ens.size();
      }
      const double ra = a * std::cos(p) - sa, rb = a * std::sin(p) - sb;
      a = std::hypot(ra, rb);
      p = std::atan2(rb, ra);
    }
    if (a > best_a)
    {
      best_a = a;
      best_f = f;
      best_p = p;
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
    c.params_json = paramsJson(c.specs.back());
  }
  return c;
}

double wrapAngle(double a)
{
  while (a > M_PI)
  {
    a -= 2 * M_PI;
  }
  while (a < -M_PI)
  {
    a += 2 * M_PI;
  }
  return a;
}
}  // namespace

std::vector<Candidate> fitCandidates(const Recording& real_fit, const std::vector<Recording>& sims_fit,
                                     const sim::Scenario& scenario)
{
  std::vector<Candidate> out;
  if (sims_fit.empty() || real_fit.size() < 64)
  {
    return out;
  }
  const double rate = scenario.rate;
  std::size_t n = real_fit.size();
  for (const auto& s : sims_fit)
  {
    n = std::min(n, s.size());
  }
  const int nseg = welchSegment(n);
  std::vector<int> allan_m;
  for (int m = 1; static_cast<std::size_t>(m) * 10 <= n; m *= 2)
  {
    allan_m.push_back(m);
  }
  const bool temp = scenario.temperature.enabled && real_fit.has_temperature;
  const FitStats R = fitStats(real_fit, rate, nseg, allan_m, temp);
  std::vector<FitStats> S(sims_fit.size());
  parallelFor(static_cast<int>(sims_fit.size()), 2,
              [&](int i) { S[i] = fitStats(sims_fit[i], rate, nseg, allan_m, temp); });
  const double t0 = real_fit.stamp.front();  // elapsed 0 of the matched scenario

  // constant_bias
  {
    Vec acc(3, 0.0), gyr(3, 0.0);
    bool any = false;
    for (int c = 0; c < kChannels; ++c)
    {
      const Cmp m = compare(R, S, [c](const FitStats& s) { return s.mean[c]; });
      if (m.significant(4.0, c < 3 ? 1e-5 : 1e-7))
      {
        (c < 3 ? acc[c] : gyr[c - 3]) = m.real - m.sim;
        any = true;
      }
    }
    if (any)
    {
      const auto ex = existing(scenario, "constant_bias");
      Vec a0 = sumParam(ex, "accel", 3), g0 = sumParam(ex, "gyro", 3);
      sim::EffectSpec e{ "constant_bias", true, {} };
      for (int i = 0; i < 3; ++i)
      {
        a0[i] += acc[i];
        g0[i] += gyr[i];
      }
      e.params["accel"] = clampVec(a0, -100, 100);
      e.params["gyro"] = clampVec(g0, -10, 10);
      out.push_back(make("constant_bias", { e }, "mean of real minus mean of the ensemble, per axis"));
    }
  }

  // white_noise: PSD floor in the upper half of the band
  {
    Vec acc(3, 0.0), gyr(3, 0.0);
    bool any = false;
    const auto ex = existing(scenario, "white_noise");
    const Vec a2 = sumSquares(ex, "accel_density"), g2 = sumSquares(ex, "gyro_density");
    for (int c = 0; c < kChannels; ++c)
    {
      auto floorOf = [c](const FitStats& s) {
        const auto& p = s.psd[c].power;
        Vec v(p.begin() + p.size() / 2, p.end() - p.size() / 20);
        return medianOf(v);
      };
      const Cmp m = compare(R, S, floorOf);
      const double base = c < 3 ? a2[c] : g2[c - 3];
      double d2 = base + (m.real - m.sim) / 2.0;
      if (m.significant(4.0) && std::abs(m.real - m.sim) > 0.1 * m.sim)
      {
        any = true;
      }
      d2 = std::max(0.0, d2);
      (c < 3 ? acc[c] : gyr[c - 3]) = std::sqrt(d2);
    }
    if (any)
    {
      sim::EffectSpec e{ "white_noise", true, {} };
      e.params["accel_density"] = clampVec(acc, 0, 10);
      e.params["gyro_density"] = clampVec(gyr, 0, 10);
      out.push_back(make("white_noise", { e }, "PSD floor (upper half band): density^2 += (P_real - P_sim) / 2"));
    }
  }

  // bias_random_walk and bias_instability: Allan variance excess. Short taus from the samples;
  // long taus from 32 block means of (recording - ensemble mean of the other runs), which takes a
  // motion common to the runs out of the long-tau Allan variance.
  if (!allan_m.empty())
  {
    const int blocks = 32;
    const std::size_t blen = n / blocks;
    const double tb = blen / rate;
    auto blockMeans = [&](const Recording& r) {
      Eigen::MatrixXd bm(blocks, kChannels);
      for (int k = 0; k < blocks; ++k)
      {
        bm.row(k) = r.data.middleRows(k * blen, blen).colwise().mean();
      }
      return bm;
    };
    const int M = static_cast<int>(sims_fit.size());
    std::vector<Eigen::MatrixXd> sb(M);
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(blocks, kChannels);
    for (int j = 0; j < M; ++j)
    {
      sb[j] = blockMeans(sims_fit[j]);
      sum += sb[j];
    }
    const Eigen::MatrixXd rb = blockMeans(real_fit) - sum / M;
    const std::vector<int> bm_m = { 1, 2, 4, 8 };
    std::vector<Vec> tau(kChannels), diff(kChannels), simv(kChannels), sims_sd(kChannels);
    for (int c = 0; c < kChannels; ++c)
    {
      for (std::size_t k = 0; k < allan_m.size(); ++k)
      {
        const double t = allan_m[k] / rate;
        if (t >= tb)
        {
          break;
        }
        const Cmp m = compare(R, S, [c, k](const FitStats& st) { return st.avar[c][k]; });
        tau[c].push_back(t);
        diff[c].push_back(m.real - m.sim);
        simv[c].push_back(std::max(m.sim, 1e-300));
        sims_sd[c].push_back(m.spread);
      }
      const Eigen::VectorXd rr = rb.col(c);
      const Vec ar = allanDeviation(rr, bm_m);
      std::vector<Vec> an(bm_m.size());
      for (int j = 0; j < M; ++j)
      {
        const Eigen::VectorXd dj = sb[j].col(c) - (sum.col(c) - sb[j].col(c)) / std::max(1, M - 1);
        const Vec a = allanDeviation(dj, bm_m);
        for (std::size_t k = 0; k < bm_m.size(); ++k)
        {
          an[k].push_back(std::isfinite(a[k]) ? a[k] * a[k] : 0.0);
        }
      }
      for (std::size_t k = 0; k < bm_m.size(); ++k)
      {
        if (!std::isfinite(ar[k]))
        {
          continue;
        }
        // (M - 1) / M: a leave-one-out residual carries more of the others' noise than the real one
        const double null = meanOf(an[k]) * (M - 1.0) / M;
        tau[c].push_back(bm_m[k] * tb);
        diff[c].push_back(ar[k] * ar[k] - null);
        simv[c].push_back(std::max(null, 1e-300));
        sims_sd[c].push_back(stdOf(an[k]));
      }
    }
    const std::size_t nt_dummy = 0;
    (void)nt_dummy;
    // random walk from the longest 3 taus
    {
      Vec acc(3, 0.0), gyr(3, 0.0);
      bool any = false;
      for (int c = 0; c < kChannels; ++c)
      {
        Vec k2;
        bool sig = false;
        const std::size_t nt = tau[c].size();
        for (std::size_t k = nt >= 3 ? nt - 3 : 0; k < nt; ++k)
        {
          const double tau_k = tau[c][k];
          if (diff[c][k] > 0)
          {
            k2.push_back(3.0 * diff[c][k] / tau_k);
          }
          sig = sig || (diff[c][k] > 4.0 * sims_sd[c][k] && diff[c][k] > 0.05 * simv[c][k]);
        }
        if (sig && !k2.empty())
        {
          (c < 3 ? acc[c] : gyr[c - 3]) = std::sqrt(medianOf(k2));
          any = true;
        }
      }
      if (any)
      {
        const auto ex = existing(scenario, "bias_random_walk");
        const Vec a2 = sumSquares(ex, "accel_density"), g2 = sumSquares(ex, "gyro_density");
        for (int i = 0; i < 3; ++i)
        {
          acc[i] = std::sqrt(acc[i] * acc[i] + a2[i]);
          gyr[i] = std::sqrt(gyr[i] * gyr[i] + g2[i]);
        }
        sim::EffectSpec e{ "bias_random_walk", true, {} };
        e.params["accel_density"] = clampVec(acc, 0, 10);
        e.params["gyro_density"] = clampVec(gyr, 0, 10);
        out.push_back(make("bias_random_walk", { e }, "Allan variance excess at the 3 longest taus = K^2 tau / 3"));
      }
    }
    // Gauss-Markov: grid over correlation times, sigma^2 by weighted least squares
    {
      std::vector<bool> sig(kChannels, false);
      bool any = false;
      for (int c = 0; c < kChannels; ++c)
      {
        for (std::size_t k = 0; k < tau[c].size(); ++k)
        {
          if (diff[c][k] > 4.0 * sims_sd[c][k] && diff[c][k] > 0.05 * simv[c][k])
          {
            sig[c] = true;
          }
        }
        any = any || sig[c];
      }
      if (any)
      {
        double best_cost = std::numeric_limits<double>::infinity();
        double best_tc = 0;
        Vec best_sigma(kChannels, 0.0);
        const double span = n / rate;
        for (double tc = 2.0 / rate; tc <= 2.0 * span; tc *= std::sqrt(2.0))
        {
          double cost = 0.0;
          Vec sigma(kChannels, 0.0);
          for (int c = 0; c < kChannels; ++c)
          {
            if (!sig[c])
            {
              continue;
            }
            double num = 0, den = 0;
            for (std::size_t k = 0; k < tau[c].size(); ++k)
            {
              const double g = gaussMarkovAllanVariance(tau[c][k], tc);
              const double w = 1.0 / (simv[c][k] + std::max(diff[c][k], 0.0));
              num += diff[c][k] * g * w * w;
              den += g * g * w * w;
            }
            const double s2 = den > 0 ? std::max(0.0, num / den) : 0.0;
            for (std::size_t k = 0; k < tau[c].size(); ++k)
            {
              const double g = gaussMarkovAllanVariance(tau[c][k], tc);
              const double w = 1.0 / (simv[c][k] + std::max(diff[c][k], 0.0));
              cost += std::pow((diff[c][k] - s2 * g) * w, 2);
            }
            sigma[c] = std::sqrt(s2);
          }
          if (cost < best_cost)
          {
            best_cost = cost;
            best_tc = tc;
            best_sigma = sigma;
          }
        }
        if (best_tc > 0 && anyNonZero(best_sigma))
        {
          std::vector<sim::EffectSpec> specs = existing(scenario, "bias_instability");
          sim::EffectSpec e{ "bias_instability", true, {} };
          e.params["accel_sigma"] = clampVec(Vec(best_sigma.begin(), best_sigma.begin() + 3), 0, 100);
          e.params["gyro_sigma"] = clampVec(Vec(best_sigma.begin() + 3, best_sigma.end()), 0, 10);
          e.params["correlation_time"] = { std::max(1e-3, best_tc) };
          specs.push_back(e);
          out.push_back(make("bias_instability", specs, "Allan variance excess fitted by a Gauss-Markov curve (grid over correlation time)"));
        }
      }
    }
  }

  // scale_factor: motion-band power ratio
  {
    Vec acc(3, 0.0), gyr(3, 0.0);
    bool any = false;
    for (int c = 0; c < kChannels; ++c)
    {
      const Cmp mm = compare(R, S, [c](const FitStats& s) { return s.mean[c]; });
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
      const auto bins = motionBins(S, c);
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
      const Cmp m = compare(R, S, power);
      if (m.sim > 0 && m.significant(4.0) && std::abs(m.real / m.sim - 1.0) > 0.002)
      {
        (c < 3 ? acc[c] : gyr[c - 3]) = m.real / m.sim - 1.0;
        any = true;
      }
    }
    if (any)
    {
      const auto ex = existing(scenario, "scale_factor");
      Vec a0(3, 1.0), g0(3, 1.0);
      for (const auto& e : ex)
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
      e.params["accel"] = clampVec(acc, -0.5, 0.5);
      e.params["gyro"] = clampVec(gyr, -0.5, 0.5);
      out.push_back(make("scale_factor", { e }, "sqrt of motion-band power ratio real / ensemble"));
    }
  }

  // misalignment: cross-spectral excess in each axis's motion band
  {
    Vec acc(9, 0.0), gyr(9, 0.0);
    bool any = false;
    // gravity axis: the mean of the others moves by M_ij g
    int jg = -1;
    for (int j = 0; j < 3; ++j)
    {
      if (std::abs(meanOf([&]() { Vec v; for (const auto& st : S) v.push_back(st.mean[j]); return v; }())) > 1.0 &&
          (jg < 0 || std::abs(S[0].mean[j]) > std::abs(S[0].mean[jg])))
      {
        jg = j;
      }
    }
    for (int s = 0; s < 2; ++s)
    {
      for (int j = 0; j < 3; ++j)
      {
        if (s == 0 && j == jg)
        {
          for (int i = 0; i < 3; ++i)
          {
            if (i == j)
            {
              continue;
            }
            const Cmp mi = compare(R, S, [i](const FitStats& st) { return st.mean[i]; });
            const Cmp mj = compare(R, S, [j](const FitStats& st) { return st.mean[j]; });
            if (mi.significant(4.0, 1e-5))
            {
              acc[3 * i + j] = (mi.real - mi.sim) / mj.sim;
              any = true;
            }
          }
          continue;
        }
        const auto bins = motionBins(S, 3 * s + j);
        if (bins.size() < 2)
        {
          continue;
        }
        for (int i = 0; i < 3; ++i)
        {
          if (i == j)
          {
            continue;
          }
          // only where axis j's motion dominates axis i's own (ensemble mean), so that i's motion
          // does not leak into the estimate
          std::vector<std::size_t> own;
          for (std::size_t k : bins)
          {
            double pjj = 0, pii = 0;
            for (const auto& st : S)
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
          const Cmp m = compare(R, S, coupling);
          if (m.significant(4.0, 1e-4))
          {
            (s == 0 ? acc : gyr)[3 * i + j] = m.real - m.sim;
            any = true;
          }
        }
      }
    }
    if (any)
    {
      const auto ex = existing(scenario, "misalignment");
      const Vec a0 = sumParam(ex, "accel", 9), g0 = sumParam(ex, "gyro", 9);
      for (int i = 0; i < 9; ++i)
      {
        acc[i] += a0[i];
        gyr[i] += g0[i];
      }
      sim::EffectSpec e{ "misalignment", true, {} };
      e.params["accel"] = clampVec(acc, -0.5, 0.5);
      e.params["gyro"] = clampVec(gyr, -0.5, 0.5);
      out.push_back(make("misalignment", { e }, "cross-spectrum excess / auto-spectrum in the motion band of each axis"));
    }
  }

  // lever_arm: regression of accel on alpha x r + omega x (omega x r), real minus ensemble
  if (R.lever_ok)
  {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
    int count = 0;
    for (const auto& s : S)
    {
      if (s.lever_ok)
      {
        mean += s.lever;
        sq += s.lever.cwiseProduct(s.lever);
        ++count;
      }
    }
    if (count >= 2)
    {
      mean /= count;
      const Eigen::Vector3d sd = (sq / count - mean.cwiseProduct(mean)).cwiseMax(0.0).cwiseSqrt() *
                                 std::sqrt(count / (count - 1.0));
      Vec d(3, 0.0);
      bool any = false;
      for (int i = 0; i < 3; ++i)
      {
        if (std::abs(R.lever[i] - mean[i]) > 4.0 * sd[i] + 0.01)
        {
          d[i] = R.lever[i] - mean[i];
          any = true;
        }
      }
      if (any)
      {
        const Vec r0 = sumParam(existing(scenario, "lever_arm"), "offset", 3);
        for (int i = 0; i < 3; ++i)
        {
          d[i] += r0[i];
        }
        sim::EffectSpec e{ "lever_arm", true, {} };
        e.params["offset"] = clampVec(d, -100, 100);
        out.push_back(make("lever_arm", { e }, "least squares of accel on alpha x r + omega x (omega x r) (omega from the gyro), real minus ensemble"));
      }
    }
  }

  // periodic_bias (one line per axis) and vibration (one line on all axes): excess lines
  {
    std::vector<Line> lines(kChannels);
    std::vector<Vec> simp(kChannels);
    for (int c = 0; c < kChannels; ++c)
    {
      simp[c] = meanPsd(S, c);
      // The ensemble's own line spread: require a clear excess over its largest member.
      Vec maxp = simp[c];
      for (const auto& s : S)
      {
        for (std::size_t k = 0; k < maxp.size(); ++k)
        {
          maxp[k] = std::max(maxp[k], s.psd_fine[c].power[k]);
        }
      }
      lines[c] = strongestLine(R.psd_fine[c], maxp, 6.0);
      if (lines[c].power > 0)
      {
        lines[c] = strongestLine(R.psd_fine[c], simp[c], 6.0);
      }
    }
    // periodic_bias
    {
      Vec amp(6, 0.0), per(6, 10.0), ph(6, 0.0);
      bool any = false;
      for (int c = 0; c < kChannels; ++c)
      {
        if (lines[c].power > 0 && lines[c].freq > 0)
        {
          double a = 0, p = 0;
          const double f = refineFrequency(real_fit, &sims_fit, c, lines[c].freq, R.psd_fine[c].df, t0, &a, &p);
          amp[c] = std::min(a, std::sqrt(2.0 * lines[c].power) * 1.5);
          per[c] = 1.0 / f;
          ph[c] = p;
          any = true;
        }
      }
      if (any)
      {
        std::vector<sim::EffectSpec> specs = existing(scenario, "periodic_bias");
        sim::EffectSpec e{ "periodic_bias", true, {} };
        e.params["accel_amplitude"] = clampVec(Vec(amp.begin(), amp.begin() + 3), 0, 100);
        e.params["gyro_amplitude"] = clampVec(Vec(amp.begin() + 3, amp.end()), 0, 10);
        e.params["accel_period"] = clampVec(Vec(per.begin(), per.begin() + 3), 1e-3, 1e7);
        e.params["gyro_period"] = clampVec(Vec(per.begin() + 3, per.end()), 1e-3, 1e7);
        e.params["accel_phase"] = Vec(ph.begin(), ph.begin() + 3);
        e.params["gyro_phase"] = Vec(ph.begin() + 3, ph.end());
        specs.push_back(e);
        out.push_back(make("periodic_bias", specs, "strongest excess spectral line per axis: amplitude sqrt(2 P), period 1 / f"));
      }
    }
    // vibration: the line with the largest excess ratio, on every axis where it shows
    {
      int cbest = -1;
      for (int c = 0; c < kChannels; ++c)
      {
        if (lines[c].power > 0 && (cbest < 0 || lines[c].ratio > lines[cbest].ratio))
        {
          cbest = c;
        }
      }
      if (cbest >= 0)
      {
        double a_ref = 0, ph_ref = 0;
        const double f = refineFrequency(real_fit, &sims_fit, cbest, lines[cbest].freq, R.psd_fine[cbest].df, t0, &a_ref, &ph_ref);
        const std::size_t k0 = lines[cbest].bin;
        Vec amp(6, 0.0);
        for (int c = 0; c < kChannels; ++c)
        {
          const auto& p = R.psd_fine[c].power;
          double pw = 0.0;
          bool shows = false;
          const std::size_t half = static_cast<std::size_t>(std::max(2.0, lines[cbest].width_bins / 2 + 1));
          for (std::size_t k = k0 > half ? k0 - half : 1; k <= std::min(p.size() - 1, k0 + half); ++k)
          {
            pw += std::max(0.0, p[k] - simp[c][k]) * R.psd_fine[c].df;
            shows = shows || p[k] > 6.0 * simp[c][k];
          }
          if (shows)
          {
            double a_c = 0, ph_c = 0;
            sinusoidFit(real_fit, c, f, t0, &a_c, &ph_c);
            const double sign = std::cos(ph_c - ph_ref) >= 0 ? 1.0 : -1.0;
            amp[c] = sign * std::min(a_c, 1.5 * std::sqrt(2.0 * pw));
          }
        }
        double a = 0, phase = 0;
        sinusoidFit(real_fit, cbest, f, t0, &a, &phase);
        double bw = 0.0;
        if (lines[cbest].width_bins > 6)
        {
          bw = (lines[cbest].width_bins - 4) * R.psd_fine[cbest].df / 2.0;
        }
        std::vector<sim::EffectSpec> specs = existing(scenario, "vibration");
        sim::EffectSpec e{ "vibration", true, {} };
        e.params["frequency"] = { f };
        e.params["accel_amplitude"] = clampVec(Vec(amp.begin(), amp.begin() + 3), -100, 100);
        e.params["gyro_amplitude"] = clampVec(Vec(amp.begin() + 3, amp.end()), -10, 10);
        e.params["phase"] = { phase };
        e.params["bandwidth"] = { bw };
        specs.push_back(e);
        out.push_back(make("vibration", specs, "strongest excess line over all axes, amplitude per axis sqrt(2 P)"));
      }
    }
  }

  // thermal_drift: slope of block means against temperature, real minus ensemble
  if (temp)
  {
    Vec acc(3, 0.0), gyr(3, 0.0);
    bool any = false;
    for (int c = 0; c < kChannels; ++c)
    {
      const Cmp m = compare(R, S, [c](const FitStats& s) { return s.temp_slope[c]; });
      if (m.significant(4.0, c < 3 ? 1e-6 : 1e-8))
      {
        (c < 3 ? acc[c] : gyr[c - 3]) = m.real - m.sim;
        any = true;
      }
    }
    if (any)
    {
      const auto ex = existing(scenario, "thermal_drift");
      const Vec a0 = sumParam(ex, "accel_coefficient", 3), g0 = sumParam(ex, "gyro_coefficient", 3);
      double ref = ex.empty() ? 20.0 : ex.front().params.at("reference_temperature")[0];
      if (ex.empty())
      {
        ref = scenario.temperature.mean;  // no information on the reference: no constant part
      }
      for (int i = 0; i < 3; ++i)
      {
        acc[i] += a0[i];
        gyr[i] += g0[i];
      }
      sim::EffectSpec e{ "thermal_drift", true, {} };
      e.params["accel_coefficient"] = clampVec(acc, -1, 1);
      e.params["gyro_coefficient"] = clampVec(gyr, -1, 1);
      e.params["reference_temperature"] = { ref };
      out.push_back(make("thermal_drift", { e }, "slope of 32 block means against temperature, real minus ensemble"));
    }
  }

  // sample_hold: readings repeated more often than in the ensemble
  {
    const Cmp m = compare(R, S, [](const FitStats& s) { return s.repeated; });
    if (m.real > 0.02 && m.real > 2.0 * m.sim + 0.01)
    {
      sim::EffectSpec e{ "sample_hold", true, {} };
      e.params["sensor_rate"] = { rate * (1.0 - m.real) };
      out.push_back(make("sample_hold", { e }, "rows repeating their predecessor: sensor rate = rate x (1 - fraction)"));
    }
  }

  // saturation: flat tops the ensemble does not have
  {
    const auto ex = existing(scenario, "saturation");
    Vec lim(6, 0.0);
    for (int c = 0; c < kChannels; ++c)
    {
      lim[c] = c < 3 ? 160.0 : 35.0;
      for (const auto& e : ex)
      {
        lim[c] = std::min(lim[c], e.params.at(c < 3 ? "accel_limit" : "gyro_limit")[c % 3]);
      }
    }
    bool any = false;
    for (int c = 0; c < kChannels; ++c)
    {
      const Cmp m = compare(R, S, [c](const FitStats& s) { return s.flat[c]; });
      if (R.flat[c] > 0 && R.limit[c] < lim[c] * 0.999 && m.real > 2.0 * m.sim + 1e-5)
      {
        lim[c] = R.limit[c];
        any = true;
      }
    }
    if (any)
    {
      sim::EffectSpec e{ "saturation", true, {} };
      e.params["accel_limit"] = Vec(lim.begin(), lim.begin() + 3);
      e.params["gyro_limit"] = Vec(lim.begin() + 3, lim.end());
      out.push_back(make("saturation", { e }, "flat tops: limit = largest magnitude, seen repeatedly"));
    }
  }

  // quantization: a lattice the ensemble does not have
  {
    const auto ex = existing(scenario, "quantization");
    Vec step = ex.empty() ? Vec(6, 0.0) : Vec{};
    if (!ex.empty())
    {
      const Vec& a = ex.back().params.at("accel_step");
      const Vec& g = ex.back().params.at("gyro_step");
      step = { a[0], a[1], a[2], g[0], g[1], g[2] };
    }
    bool any = false;
    for (int c = 0; c < kChannels; ++c)
    {
      double sim_step = 0.0;
      for (const auto& s : S)
      {
        sim_step = std::max(sim_step, s.lattice[c]);
      }
      if (R.lattice[c] > 0 && std::abs(R.lattice[c] - sim_step) > 1e-3 * R.lattice[c])
      {
        step[c] = R.lattice[c];
        any = true;
      }
    }
    if (any)
    {
      sim::EffectSpec e{ "quantization", true, {} };
      e.params["accel_step"] = clampVec(Vec(step.begin(), step.begin() + 3), 0, 100);
      e.params["gyro_step"] = clampVec(Vec(step.begin() + 3, step.end()), 0, 10);
      out.push_back(make("quantization", { e }, "values on a lattice: step = smallest gap between distinct values"));
    }
  }

  // gravity_leakage: horizontal specific force in the REPORTED frame, real minus ensemble
  if (R.has_leak && S[0].has_leak)
  {
    const Cmp e = compare(R, S, [](const FitStats& s) { return s.leak_e; });
    const Cmp nn = compare(R, S, [](const FitStats& s) { return s.leak_n; });
    const Cmp y = compare(R, S, [](const FitStats& s) { return s.yaw; });
    const bool sig_tilt = e.significant(4.0, 2e-4) || nn.significant(4.0, 2e-4);
    const double dyaw = wrapAngle(y.real - y.sim);
    const bool sig_yaw = std::abs(dyaw) > 4.0 * y.spread + 2e-4;
    if (sig_tilt || sig_yaw)
    {
      const double de = e.real - e.sim, dn = nn.real - nn.sim;
      const double c = std::cos(R.yaw), s = std::sin(R.yaw);
      const double bx = c * de + s * dn;   // body x (forward) component of the leak
      const double by = -s * de + c * dn;  // body y (left)
      const auto ex = existing(scenario, "gravity_leakage");
      const Vec r0 = sumParam(ex, "roll", 1), p0 = sumParam(ex, "pitch", 1), y0 = sumParam(ex, "yaw", 1);
      sim::EffectSpec spec{ "gravity_leakage", true, {} };
      spec.params["roll"] = { std::max(-1.5, std::min(1.5, r0[0] + (sig_tilt ? -by : 0.0))) };
      spec.params["pitch"] = { std::max(-1.5, std::min(1.5, p0[0] + (sig_tilt ? bx : 0.0))) };
      spec.params["yaw"] = { std::max(-3.2, std::min(3.2, y0[0] + (sig_yaw ? dyaw : 0.0))) };
      out.push_back(make("gravity_leakage", { spec }, "mean specific force rotated by the reported orientation: horizontal part / g = tilt error"));
    }
  }

  // timestamp_jitter
  {
    const Cmp j = compare(R, S, [](const FitStats& s) { return s.stamps.jitter; });
    if (j.real > 3.0 * j.sim + 4.0 * j.spread + 1e-7)
    {
      const auto ex = existing(scenario, "timestamp_jitter");
      const double off = ex.empty() ? 0.0 : ex.back().params.at("offset")[0];
      sim::EffectSpec e{ "timestamp_jitter", true, {} };
      e.params["sigma"] = { std::min(1.0, j.real) };
      e.params["offset"] = { off };
      out.push_back(make("timestamp_jitter", { e }, "robust std of stamps about a straight line in the sample index"));
    }
  }

  // dropouts
  {
    const Cmp l = compare(R, S, [](const FitStats& s) { return s.stamps.lost_fraction; });
    if (l.real > 2.0 * l.sim + 4.0 * l.spread + 1e-4 && R.stamps.bursts > 0)
    {
      const double kept = static_cast<double>(real_fit.size());
      sim::EffectSpec e{ "dropouts", true, {} };
      e.params["probability"] = { std::min(1.0, R.stamps.bursts / kept) };
      e.params["burst_length"] = { std::max(1.0, R.stamps.mean_burst) };
      out.push_back(make("dropouts", { e }, "gaps in the stamps: bursts per kept sample, mean missing per gap"));
    }
  }
  return out;
}
}  // namespace periodic_bias_compensation::gap
