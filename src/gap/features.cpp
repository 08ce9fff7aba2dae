// Features of a recording and their distance from a simulated ensemble.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/gap/features.h"
#include "periodic_bias_compensation/gap/signal.h"

namespace periodic_bias_compensation::gap
{
namespace
{
std::string fmt(const char* f, double a, double b = 0.0)
{
  char buf[96];
  std::snprintf(buf, sizeof(buf), f, a, b);
  return buf;
}

double lg(double v)
{
  return std::log10(std::max(v, 1e-300));
}

bool isAccel(int c)
{
  return c < 3;
}
}  // namespace

FeatureLayout makeLayout(double rate, std::size_t n, bool orientation, bool temperature, int segments)
{
  FeatureLayout L;
  L.rate = rate;
  L.nseg = welchSegment(n);
  L.segments = segments;
  L.orientation = orientation;
  L.temperature = temperature;
  const double df = rate / L.nseg;
  std::vector<double> edges{ rate / 2.0 };
  while (edges.back() / std::sqrt(2.0) >= 0.99 * df)
  {
    edges.push_back(edges.back() / std::sqrt(2.0));
  }
  std::reverse(edges.begin(), edges.end());
  L.band_edges = edges;
  for (int m = 1; static_cast<std::size_t>(m) * 10 <= n; m *= 2)
  {
    L.allan_m.push_back(m);
  }
  const auto& names = channelNames();
  for (int c = 0; c < kChannels; ++c)
  {
    const double abs_floor = isAccel(c) ? 1e-6 : 1e-7;
    for (std::size_t b = 0; b + 1 < edges.size(); ++b)
    {
      L.info.push_back({ names[c], "psd", fmt("%.3g-%.3g Hz", edges[b], edges[b + 1]), edges[b], edges[b + 1], "all",
                         "sensor", 0.012, 0.0 });
    }
    for (int m : L.allan_m)
    {
      L.info.push_back(
          { names[c], "allan", fmt("tau %.3g s", m / rate), m / rate, m / rate, "all", "sensor", 0.012, 0.0 });
    }
    L.info.push_back({ names[c], "mean", "", 0, 0, "all", "sensor", abs_floor, 2e-5 });
    L.info.push_back({ names[c], "log_std", "", 0, 0, "all", "sensor", 0.003, 0.0 });
    for (int s = 0; s < segments; ++s)
    {
      const std::string seg = "seg " + std::to_string(s + 1) + "/" + std::to_string(segments);
      L.info.push_back({ names[c], "mean", "", 0, 0, seg, "sensor", abs_floor, 2e-5 });
      L.info.push_back({ names[c], "log_std", "", 0, 0, seg, "sensor", 0.005, 0.0 });
    }
    L.info.push_back({ names[c], "flat_top", "", 0, 0, "all", "sensor", 2e-4, 0.0 });
    L.info.push_back({ names[c], "lattice", "", 0, 0, "all", "sensor", 0.1, 0.0 });
    if (temperature)
    {
      L.info.push_back({ names[c], "temp_slope", "", 0, 0, "all", "sensor", isAccel(c) ? 1e-5 : 1e-7, 0.0 });
    }
  }
  const char* pairs[3] = { "xy", "xz", "yz" };
  for (int s = 0; s < 2; ++s)
  {
    for (int p = 0; p < 3; ++p)
    {
      L.info.push_back(
          { std::string(s == 0 ? "accel " : "gyro ") + pairs[p], "corr", "", 0, 0, "all", "sensor", 0.01, 0.0 });
    }
  }
  L.info.push_back({ "stamp", "log_jitter", "", 0, 0, "all", "stamps", 0.1, 0.0 });
  L.info.push_back({ "stamp", "lost_fraction", "", 0, 0, "all", "stamps", 2e-4, 0.0 });
  L.info.push_back({ "stamp", "backwards_fraction", "", 0, 0, "all", "stamps", 1e-4, 0.0 });
  if (orientation)
  {
    L.info.push_back({ "orientation", "leak_east", "", 0, 0, "all", "orientation", 2e-4, 0.0 });
    L.info.push_back({ "orientation", "leak_north", "", 0, 0, "all", "orientation", 2e-4, 0.0 });
    L.info.push_back({ "orientation", "yaw_mean", "", 0, 0, "all", "orientation", 2e-4, 0.0 });
  }
  return L;
}

std::vector<double> computeFeatures(const Recording& r, const FeatureLayout& L)
{
  std::vector<double> f;
  f.reserve(L.info.size());
  const std::size_t n = r.size();
  const double rate = L.rate;
  for (int c = 0; c < kChannels; ++c)
  {
    const Eigen::VectorXd x = r.data.col(c);
    const Psd psd = welch(x, rate, L.nseg);
    for (std::size_t b = 0; b + 1 < L.band_edges.size(); ++b)
    {
      double sum = 0.0;
      int count = 0;
      for (std::size_t k = 1; k < psd.power.size(); ++k)
      {
        const double fk = k * psd.df;
        if (fk >= L.band_edges[b] &&
            (fk < L.band_edges[b + 1] || (b + 2 == L.band_edges.size() && fk <= L.band_edges[b + 1])))
        {
          sum += psd.power[k];
          ++count;
        }
      }
      f.push_back(lg(count > 0 ? sum / count : 0.0));
    }
    const std::vector<double> adev = allanDeviation(x, L.allan_m);
    for (double a : adev)
    {
      f.push_back(std::isfinite(a) ? lg(a) : -300.0);
    }
    const double mean = n > 0 ? x.mean() : 0.0;
    const double sd = n > 1 ? std::sqrt((x.array() - mean).square().mean()) : 0.0;
    f.push_back(mean);
    f.push_back(lg(sd));
    for (int s = 0; s < L.segments; ++s)
    {
      const std::size_t a = n * s / L.segments;
      const std::size_t b = n * (s + 1) / L.segments;
      if (b <= a)
      {
        f.push_back(0.0);
        f.push_back(-300.0);
        continue;
      }
      const auto seg = x.segment(a, b - a);
      const double m = seg.mean();
      f.push_back(m);
      f.push_back(lg(std::sqrt((seg.array() - m).square().mean())));
    }
    f.push_back(flatTopFraction(x));
    f.push_back(latticeStep(x) > 0.0 ? 1.0 : 0.0);
    if (L.temperature)
    {
      double slope = 0.0;
      if (r.has_temperature && r.temperature.size() == n && n > 64)
      {
        const int blocks = 32;
        std::vector<double> xb(blocks), tb(blocks);
        for (int k = 0; k < blocks; ++k)
        {
          const std::size_t a = n * k / blocks, b = n * (k + 1) / blocks;
          double sx = 0, st = 0;
          for (std::size_t i = a; i < b; ++i)
          {
            sx += x[i];
            st += r.temperature[i];
          }
          xb[k] = sx / (b - a);
          tb[k] = st / (b - a);
        }
        double mx = 0, mt = 0;
        for (int k = 0; k < blocks; ++k)
        {
          mx += xb[k] / blocks;
          mt += tb[k] / blocks;
        }
        double cov = 0, var = 0;
        for (int k = 0; k < blocks; ++k)
        {
          cov += (xb[k] - mx) * (tb[k] - mt);
          var += (tb[k] - mt) * (tb[k] - mt);
        }
        slope = var > 1e-9 ? cov / var : 0.0;
      }
      f.push_back(slope);
    }
  }
  for (int s = 0; s < 2; ++s)
  {
    const int pa[3] = { 0, 0, 1 }, pb[3] = { 1, 2, 2 };
    for (int p = 0; p < 3; ++p)
    {
      const Eigen::VectorXd a = r.data.col(3 * s + pa[p]).array() - r.data.col(3 * s + pa[p]).mean();
      const Eigen::VectorXd b = r.data.col(3 * s + pb[p]).array() - r.data.col(3 * s + pb[p]).mean();
      const double den = std::sqrt(a.squaredNorm() * b.squaredNorm());
      f.push_back(den > 0 ? a.dot(b) / den : 0.0);
    }
  }
  const StampStats st = stampStats(r.stamp, rate);
  f.push_back(lg(st.jitter + 1e-7));
  f.push_back(st.lost_fraction);
  f.push_back(n > 1 ? st.backwards / (n - 1) : 0.0);
  if (L.orientation)
  {
    Eigen::Vector3d fe = Eigen::Vector3d::Zero();
    Eigen::Vector2d heading = Eigen::Vector2d::Zero();
    if (r.has_orientation && r.orientation.size() == n && n > 0)
    {
      for (std::size_t i = 0; i < n; ++i)
      {
        const Eigen::Vector3d fb = r.data.row(i).head<3>().transpose();
        fe += r.orientation[i] * fb;
        const Eigen::Vector3d xaxis = r.orientation[i] * Eigen::Vector3d::UnitX();
        heading += Eigen::Vector2d(xaxis.x(), xaxis.y());
      }
      fe /= static_cast<double>(n);
    }
    const double g = std::max(fe.norm(), 1e-9);
    f.push_back(fe.x() / g);
    f.push_back(fe.y() / g);
    f.push_back(std::atan2(heading.y(), heading.x()));
  }
  return f;
}

EnsembleStats ensembleStats(const std::vector<std::vector<double>>& members, const FeatureLayout& L)
{
  EnsembleStats s;
  const std::size_t nf = L.info.size();
  s.median.resize(nf);
  s.spread.resize(nf);
  s.left_out.resize(nf);
  for (std::size_t i = 0; i < nf; ++i)
  {
    std::vector<double> v;
    for (const auto& m : members)
    {
      v.push_back(m[i]);
    }
    const double med = median(v);
    std::vector<double> dev;
    double mean = 0.0;
    for (double a : v)
    {
      dev.push_back(std::abs(a - med));
      mean += a / v.size();
    }
    double var = 0.0;
    for (double a : v)
    {
      var += (a - mean) * (a - mean) / std::max<double>(1.0, v.size() - 1.0);
    }
    const double mad = 1.4826 * median(dev);
    s.median[i] = med;
    s.spread[i] = std::max({ mad, std::sqrt(var), L.info[i].floor + L.info[i].rel_floor * std::abs(med) });
    s.left_out[i] = L.info[i].left_out;
    if (L.info[i].left_out)
    {
      s.spread[i] = 1.0;  // no spread penalty (gapOf) on a feature that does not count
    }
  }
  return s;
}

std::vector<double> zScores(const std::vector<double>& features, const EnsembleStats& stats)
{
  std::vector<double> z(features.size());
  for (std::size_t i = 0; i < features.size(); ++i)
  {
    const double d = features[i] - stats.median[i];
    const bool left_out = i < stats.left_out.size() && stats.left_out[i];
    z[i] = std::isfinite(d) && !left_out ? d / stats.spread[i] : 0.0;
    z[i] = std::max(-1e4, std::min(1e4, z[i]));
  }
  return z;
}

double gapOf(const std::vector<double>& z)
{
  if (z.empty())
  {
    return 0.0;
  }
  double sum = 0.0;
  for (double v : z)
  {
    const double e = std::log1p(std::max(0.0, std::abs(v) - kZThreshold));
    sum += e * e;
  }
  return std::sqrt(sum / z.size());
}

double gapOf(const std::vector<double>& z, const std::vector<double>& spread, const std::vector<double>& base_spread)
{
  if (z.empty())
  {
    return 0.0;
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < z.size(); ++i)
  {
    double e = std::log1p(std::max(0.0, std::abs(z[i]) - kZThreshold));
    if (i < spread.size() && i < base_spread.size() && base_spread[i] > 0)
    {
      e += kSpreadPenalty * std::max(0.0, std::log(spread[i] / base_spread[i]));
    }
    sum += e * e;
  }
  return std::sqrt(sum / z.size());
}

std::vector<double> leaveOneOutZ(const std::vector<std::vector<double>>& members, int i, const FeatureLayout& layout)
{
  std::vector<std::vector<double>> rest;
  for (int j = 0; j < static_cast<int>(members.size()); ++j)
  {
    if (j != i)
    {
      rest.push_back(members[j]);
    }
  }
  return zScores(members[i], ensembleStats(rest, layout));
}

OwnShrink ownShrink(const std::vector<double>& real, const EnsembleStats& base, const EnsembleStats& candidate,
                    const std::vector<std::vector<double>>& null_z)
{
  OwnShrink own;
  std::vector<std::size_t> moved;
  for (std::size_t k = 0; k < base.median.size() && k < candidate.median.size(); ++k)
  {
    const bool left_out = k < base.left_out.size() && base.left_out[k];
    if (!left_out && std::abs(candidate.median[k] - base.median[k]) > kMovedSpreads * base.spread[k])
    {
      moved.push_back(k);
    }
  }
  own.moved = static_cast<int>(moved.size());
  if (moved.empty())
  {
    return own;
  }
  const auto over_moved = [&moved](const std::vector<double>& values) {
    std::vector<double> out;
    for (std::size_t k : moved)
    {
      out.push_back(values[k]);
    }
    return out;
  };
  own.before = gapOf(over_moved(zScores(real, base)));
  own.after = gapOf(over_moved(zScores(real, candidate)), over_moved(candidate.spread), over_moved(base.spread));
  std::vector<double> nulls;
  for (const std::vector<double>& z : null_z)
  {
    nulls.push_back(gapOf(over_moved(z)));
  }
  if (!nulls.empty())
  {
    std::sort(nulls.begin(), nulls.end());
    own.null_level = nulls[nulls.size() / 2];
  }
  const double excess = own.before - own.null_level;
  own.shrink = excess > 0.0 ? std::min(1.0, (own.before - own.after) / excess) : 0.0;
  return own;
}

std::vector<Departure> rankDepartures(const std::vector<double>& real, const EnsembleStats& stats,
                                      const FeatureLayout& layout, double threshold, std::size_t max_count)
{
  const std::vector<double> z = zScores(real, stats);
  std::vector<Departure> out;
  for (std::size_t i = 0; i < z.size(); ++i)
  {
    if (std::abs(z[i]) > threshold)
    {
      out.push_back({ layout.info[i], real[i], stats.median[i], z[i] });
    }
  }
  std::sort(out.begin(), out.end(),
            [](const Departure& a, const Departure& b) { return std::abs(a.z) > std::abs(b.z); });
  if (out.size() > max_count)
  {
    out.resize(max_count);
  }
  return out;
}
}  // namespace periodic_bias_compensation::gap
