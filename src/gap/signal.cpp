// Signal processing of the gap diagnosis: Welch PSD (FFTW3), Allan deviation, lattices,
// flat tops, stamp statistics; recordings from the simulator.
#include <fftw3.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "periodic_bias_compensation/common/fftw_planner.h"
#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/gap/recording.h"
#include "periodic_bias_compensation/gap/signal.h"
#include "periodic_bias_compensation/sim/simulator.h"

namespace periodic_bias_compensation::gap
{
namespace
{
/// FFTW real-to-complex plan for one length (planning is not thread-safe: under a mutex).
class RealFft
{
public:
  explicit RealFft(int n) : n_(n)
  {
    in_ = fftw_alloc_real(n);
    out_ = fftw_alloc_complex(n / 2 + 1);
    std::lock_guard<std::mutex> lock(fftwPlannerMutex());
    plan_ = fftw_plan_dft_r2c_1d(n, in_, out_, FFTW_ESTIMATE);
  }
  ~RealFft()
  {
    std::lock_guard<std::mutex> lock(fftwPlannerMutex());
    fftw_destroy_plan(plan_);
    fftw_free(in_);
    fftw_free(out_);
  }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;
  double* in()
  {
    return in_;
  }
  std::complex<double> out(int k) const
  {
    return { out_[k][0], out_[k][1] };
  }
  void run()
  {
    fftw_execute(plan_);
  }

private:
  int n_;
  double* in_;
  fftw_complex* out_;
  fftw_plan plan_;
};

std::vector<double> hann(int n)
{
  std::vector<double> w(n);
  for (int i = 0; i < n; ++i)
  {
    w[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * i / n);
  }
  return w;
}
}  // namespace

const std::array<std::string, kChannels>& channelNames()
{
  static const std::array<std::string, kChannels> names{ { "ax", "ay", "az", "gx", "gy", "gz" } };
  return names;
}

void parallelFor(int n, int threads, const std::function<void(int)>& fn)
{
  threads = std::max(1, std::min(threads, n));
  if (threads == 1)
  {
    for (int i = 0; i < n; ++i)
    {
      fn(i);
    }
    return;
  }
  std::atomic<int> next{ 0 };
  std::exception_ptr error;
  std::mutex error_mutex;
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
  {
    pool.emplace_back([&]() {
      for (int i = next++; i < n; i = next++)
      {
        try
        {
          fn(i);
        }
        catch (...)
        {
          std::lock_guard<std::mutex> lock(error_mutex);
          error = std::current_exception();
        }
      }
    });
  }
  for (auto& th : pool)
  {
    th.join();
  }
  if (error)
  {
    std::rethrow_exception(error);
  }
}

int welchSegment(std::size_t n)
{
  int nseg = 16;
  while (static_cast<std::size_t>(nseg) * 2 <= n / 4 && nseg < (1 << 15))
  {
    nseg *= 2;
  }
  return nseg;
}

Psd welch(const Eigen::Ref<const Eigen::VectorXd>& x, double rate, int nseg)
{
  Psd psd;
  const int n = static_cast<int>(x.size());
  nseg = std::max(2, std::min(nseg, n));
  psd.df = rate / nseg;
  psd.power.assign(nseg / 2 + 1, 0.0);
  if (n < 2)
  {
    return psd;
  }
  const std::vector<double> w = hann(nseg);
  double wsum2 = 0.0;
  for (double v : w)
  {
    wsum2 += v * v;
  }
  RealFft fft(nseg);
  const int hop = std::max(1, nseg / 2);
  int count = 0;
  for (int start = 0; start + nseg <= n; start += hop)
  {
    const double mean = x.segment(start, nseg).mean();
    for (int i = 0; i < nseg; ++i)
    {
      fft.in()[i] = (x[start + i] - mean) * w[i];
    }
    fft.run();
    for (int k = 0; k <= nseg / 2; ++k)
    {
      psd.power[k] += std::norm(fft.out(k));
    }
    ++count;
  }
  const double scale = 1.0 / (std::max(count, 1) * rate * wsum2);
  for (int k = 0; k <= nseg / 2; ++k)
  {
    const bool edge = (k == 0) || (k == nseg / 2 && nseg % 2 == 0);
    psd.power[k] *= scale * (edge ? 1.0 : 2.0);
  }
  return psd;
}

std::vector<Eigen::Matrix3d> welchCross3(const Eigen::Ref<const Eigen::MatrixXd>& x3, double rate, int nseg)
{
  const int n = static_cast<int>(x3.rows());
  nseg = std::max(2, std::min(nseg, n));
  std::vector<Eigen::Matrix3d> out(nseg / 2 + 1, Eigen::Matrix3d::Zero());
  if (n < 2)
  {
    return out;
  }
  const std::vector<double> w = hann(nseg);
  double wsum2 = 0.0;
  for (double v : w)
  {
    wsum2 += v * v;
  }
  std::array<std::unique_ptr<RealFft>, 3> fft;
  for (auto& f : fft)
  {
    f = std::make_unique<RealFft>(nseg);
  }
  const int hop = std::max(1, nseg / 2);
  int count = 0;
  for (int start = 0; start + nseg <= n; start += hop)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double mean = x3.col(c).segment(start, nseg).mean();
      for (int i = 0; i < nseg; ++i)
      {
        fft[c]->in()[i] = (x3(start + i, c) - mean) * w[i];
      }
      fft[c]->run();
    }
    for (int k = 0; k <= nseg / 2; ++k)
    {
      for (int a = 0; a < 3; ++a)
      {
        for (int b = 0; b < 3; ++b)
        {
          out[k](a, b) += std::real(fft[a]->out(k) * std::conj(fft[b]->out(k)));
        }
      }
    }
    ++count;
  }
  const double scale = 2.0 / (std::max(count, 1) * rate * wsum2);
  for (auto& m : out)
  {
    m *= scale;
  }
  return out;
}

std::vector<double> allanDeviation(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<int>& ms)
{
  const std::size_t n = x.size();
  // Cumulative sum (of values minus their mean, for precision).
  const double mean = n > 0 ? x.mean() : 0.0;
  std::vector<double> c(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i)
  {
    c[i + 1] = c[i] + (x[i] - mean);
  }
  std::vector<double> out;
  for (int m : ms)
  {
    if (m < 1 || n < static_cast<std::size_t>(2 * m + 1))
    {
      out.push_back(std::nan(""));
      continue;
    }
    double sum = 0.0;
    const std::size_t count = n - 2 * m + 1;
    for (std::size_t k = 0; k < count; ++k)
    {
      const double d = c[k + 2 * m] - 2.0 * c[k + m] + c[k];
      sum += d * d;
    }
    out.push_back(std::sqrt(sum / (2.0 * m * m * count)));
  }
  return out;
}

double gaussMarkovAllanVariance(double tau, double tc)
{
  const double x = tau / tc;
  if (x < 1e-4)
  {
    return 2.0 * tau / (3.0 * tc);
  }
  return 2.0 * tc / tau * (1.0 - (3.0 - 4.0 * std::exp(-x) + std::exp(-2.0 * x)) / (2.0 * x));
}

double latticeStep(const Eigen::Ref<const Eigen::VectorXd>& x)
{
  const std::size_t n = x.size();
  if (n < 20)
  {
    return 0.0;
  }
  if (n > 16384)
  {
    // Quick rejection on ~8192 strided samples: continuous values are nearly all distinct there
    // (a lattice would need over 40 000 levels in use to look so).
    std::vector<double> p;
    for (std::size_t i = 0; i < n; i += n / 8192)
    {
      p.push_back(x[i]);
    }
    std::sort(p.begin(), p.end());
    if (static_cast<double>(std::unique(p.begin(), p.end()) - p.begin()) > 0.9 * p.size())
    {
      return 0.0;
    }
  }
  const std::size_t stride = std::max<std::size_t>(1, n / 100000);
  std::vector<double> v;
  for (std::size_t i = 0; i < n; i += stride)
  {
    v.push_back(x[i]);
  }
  std::sort(v.begin(), v.end());
  std::vector<double> u;
  for (double a : v)
  {
    if (u.empty() || a != u.back())
    {
      u.push_back(a);
    }
  }
  if (u.size() < 2 || u.size() * 2 > v.size())
  {
    return 0.0;
  }
  double q = std::numeric_limits<double>::infinity();
  const double span = std::max(std::abs(u.front()), std::abs(u.back()));
  for (std::size_t i = 1; i < u.size(); ++i)
  {
    const double d = u[i] - u[i - 1];
    if (d > 1e-12 * std::max(span, 1e-300))
    {
      q = std::min(q, d);
    }
  }
  if (!std::isfinite(q) || q <= 0.0)
  {
    return 0.0;
  }
  std::size_t on = 0;
  for (double a : v)
  {
    const double r = a / q;
    on += std::abs(r - std::round(r)) < 1e-3 ? 1 : 0;
  }
  return on >= 0.99 * v.size() ? q : 0.0;
}

double flatTopFraction(const Eigen::Ref<const Eigen::VectorXd>& x, double* limit)
{
  if (x.size() == 0)
  {
    return 0.0;
  }
  const double m = x.cwiseAbs().maxCoeff();
  if (limit != nullptr)
  {
    *limit = m;
  }
  if (m <= 0.0)
  {
    return 0.0;
  }
  std::size_t count = 0, runs = 0;
  bool previous_at_limit = false;
  for (Eigen::Index i = 0; i < x.size(); ++i)
  {
    const bool at_limit = std::abs(x[i]) >= m * (1.0 - 1e-12);
    count += at_limit ? 1 : 0;
    runs += at_limit && !previous_at_limit ? 1 : 0;
    previous_at_limit = at_limit;
  }
  // Clipping reaches the limit again and again; one held reading at the peak is one run.
  return count < 3 || runs < 2 ? 0.0 : static_cast<double>(count) / x.size();
}

double repeatedFraction(const Eigen::MatrixXd& data)
{
  if (data.rows() < 2)
  {
    return 0.0;
  }
  Eigen::Index repeated = 0;
  for (Eigen::Index i = 1; i < data.rows(); ++i)
  {
    repeated += data.row(i) == data.row(i - 1) ? 1 : 0;
  }
  return static_cast<double>(repeated) / (data.rows() - 1);
}

namespace
{
/// Mean of exp(2 pi i f (t - t0)) over stamp[from, to): its angle is the stamps' phase against
/// the trial rate f, its length their coherence (1 without jitter, whatever was lost).
std::complex<double> stampPhasor(const std::vector<double>& stamp, double f, std::size_t from, std::size_t to)
{
  std::complex<double> sum = 0.0;
  for (std::size_t i = from; i < to; ++i)
  {
    double x = f * (stamp[i] - stamp[0]);
    x -= std::floor(x);
    sum += std::polar(1.0, 2.0 * M_PI * x);
  }
  return to > from ? sum / static_cast<double>(to - from) : sum;
}

/// The rate f corrected by the drift of the stamps' phase from block to block: against a rate
/// off by d, the phase turns by -2 pi d per second. Lost samples leave the phase as it is.
double refineRate(const std::vector<double>& stamp, double f, std::size_t block)
{
  double sw = 0, st = 0, sp = 0, stt = 0, stp = 0;
  double previous = 0.0;
  bool first = true;
  for (std::size_t from = 0; from + block <= stamp.size(); from += block)
  {
    const std::complex<double> z = stampPhasor(stamp, f, from, from + block);
    if (std::abs(z) < 0.3)
    {
      continue;  // too blurred to carry a phase
    }
    const double phase = first ? std::arg(z) : previous + wrapAngle(std::arg(z) - previous);
    first = false;
    previous = phase;
    const double tau = 0.5 * (stamp[from] + stamp[from + block - 1]) - stamp[0];
    sw += 1.0;
    st += tau;
    sp += phase;
    stt += tau * tau;
    stp += tau * phase;
  }
  const double det = sw * stt - st * st;
  if (sw < 2.0 || !(det > 0.0))
  {
    return f;
  }
  const double slope = (sw * stp - st * sp) / det;
  return f - slope / (2.0 * M_PI);
}

/// The sample indices: each stamp's nearest index on the line u = f (t - t0) - c, or one either
/// side, chosen so that the indices increase and the residuals (of spread `sigma`, in periods)
/// and the lost samples (each as unlikely as a residual of 3.7 sigma) cost least (Viterbi).
std::vector<double> assignIndices(const std::vector<double>& stamp, double f, double c, double sigma)
{
  const std::size_t n = stamp.size();
  constexpr int kCandidates = 4;  // nearest - 1, nearest, nearest + 1, best predecessor + 1
  const double loss = 2.0 * std::log(1000.0);
  std::vector<std::array<double, kCandidates>> k(n);
  std::vector<std::array<signed char, kCandidates>> from(n);
  std::array<double, kCandidates> cost{};
  int best = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double u = f * (stamp[i] - stamp[0]) - c;
    const double nearest = std::round(u);
    k[i] = { nearest - 1.0, nearest, nearest + 1.0, i == 0 ? nearest : k[i - 1][best] + 1.0 };
    std::array<double, kCandidates> next{};
    for (int q = 0; q < kCandidates; ++q)
    {
      const double r = (u - k[i][q]) / sigma;
      double step = i == 0 ? 0.0 : std::numeric_limits<double>::infinity();
      from[i][q] = 0;
      for (int p = 0; i > 0 && p < kCandidates; ++p)
      {
        const double gap = k[i][q] - k[i - 1][p] - 1.0;
        const double c_step = gap < 0.0 ? std::numeric_limits<double>::infinity() : cost[p] + gap * loss;
        if (c_step < step)
        {
          step = c_step;
          from[i][q] = static_cast<signed char>(p);
        }
      }
      next[q] = step + r * r;
    }
    cost = next;
    best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  }
  std::vector<double> index(n);
  for (std::size_t i = n; i-- > 0;)
  {
    index[i] = k[i][best];
    best = from[i][best];
  }
  const double k0 = index.empty() ? 0.0 : index[0];
  for (double& v : index)
  {
    v -= k0;
  }
  return index;
}

/// Least-squares line stamp = a + b k, refitted once without the residuals beyond 5 robust
/// standard deviations (a stamp delayed by a stalled driver does not tilt it).
std::pair<double, double> trimmedLine(const std::vector<double>& stamp, const std::vector<double>& k)
{
  const std::size_t n = stamp.size();
  std::vector<char> use(n, 1);
  double a = 0.0, b = 0.0;
  for (int pass = 0; pass < 2; ++pass)
  {
    double sw = 0, sk = 0, st = 0, skk = 0, skt = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      if (use[i])
      {
        const double t = stamp[i] - stamp[0];
        sw += 1.0;
        sk += k[i];
        st += t;
        skk += k[i] * k[i];
        skt += k[i] * t;
      }
    }
    b = (sw * skt - sk * st) / std::max(sw * skk - sk * sk, 1e-300);
    a = (st - b * sk) / sw;
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n; ++i)
    {
      r[i] = std::abs(stamp[i] - stamp[0] - a - b * k[i]);
    }
    std::vector<double> sorted = r;
    const double limit = 5.0 * 1.4826 * upperMedian(sorted.begin(), sorted.end()) + 1e-12;
    for (std::size_t i = 0; i < n; ++i)
    {
      use[i] = r[i] <= limit ? 1 : 0;
    }
  }
  return { stamp[0] + a, b };
}

/// The median interval's rate [Hz] (0 without a positive one).
double medianIntervalRate(const std::vector<double>& stamp)
{
  std::vector<double> dt;
  dt.reserve(stamp.size());
  for (std::size_t i = 1; i < stamp.size(); ++i)
  {
    dt.push_back(stamp[i] - stamp[i - 1]);
  }
  const double med = dt.empty() ? 0.0 : median(std::move(dt));
  return med > 0.0 ? 1.0 / med : 0.0;
}
}  // namespace

StampLine fitStampLine(const std::vector<double>& stamp, double rate)
{
  StampLine line;
  const std::size_t n = stamp.size();
  if (n < 3 || !(rate > 0.0))
  {
    line.index.resize(n);
    for (std::size_t i = 0; i < n; ++i)
    {
      line.index[i] = static_cast<double>(i);
    }
    line.offset = n > 0 ? stamp[0] : 0.0;
    line.period = rate > 0.0 ? 1.0 / rate : 0.0;
    return line;
  }
  // Stamps on an exact grid (a simulated run without stamp effects): every index is the next.
  bool regular = true;
  for (std::size_t i = 1; i < n && regular; ++i)
  {
    regular = std::abs((stamp[i] - stamp[i - 1]) * rate - 1.0) < 1e-6;
  }
  if (regular)
  {
    line.index.resize(n);
    for (std::size_t i = 0; i < n; ++i)
    {
      line.index[i] = static_cast<double>(i);
    }
    std::tie(line.offset, line.period) = trimmedLine(stamp, line.index);
    return line;
  }
  double f = refineRate(stamp, rate, 256);
  f = refineRate(stamp, f, std::max<std::size_t>(256, n / 32));
  const std::complex<double> z = stampPhasor(stamp, f, 0, n);
  const double coherence = std::clamp(std::abs(z), 1e-3, 1.0 - 1e-9);
  const double sigma = std::clamp(std::sqrt(-2.0 * std::log(coherence)) / (2.0 * M_PI), 0.02, 0.3);
  line.index = assignIndices(stamp, f, std::arg(z) / (2.0 * M_PI), sigma);
  std::tie(line.offset, line.period) = trimmedLine(stamp, line.index);
  return line;
}

double estimateRate(const Recording& recording)
{
  const double guess = medianIntervalRate(recording.stamp);
  const StampLine line = fitStampLine(recording.stamp, guess);
  return line.period > 0.0 ? 1.0 / line.period : guess;
}

StampStats stampStats(const std::vector<double>& stamp, double rate)
{
  StampStats s;
  const std::size_t n = stamp.size();
  if (n < 3 || rate <= 0.0)
  {
    return s;
  }
  for (std::size_t i = 1; i < n; ++i)
  {
    s.backwards += stamp[i] < stamp[i - 1] ? 1.0 : 0.0;
  }
  const StampLine line = fitStampLine(stamp, rate);
  const std::vector<double>& k = line.index;
  s.rate = line.period > 0.0 ? 1.0 / line.period : 0.0;
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    r[i] = stamp[i] - (line.offset + line.period * k[i]);
  }
  const double med = upperMedian(r.begin(), r.end());
  for (double& v : r)
  {
    v = std::abs(v - med);
  }
  s.jitter = 1.4826 * upperMedian(r.begin(), r.end());
  double missing = 0.0;
  for (std::size_t i = 1; i < n; ++i)
  {
    const double gap = k[i] - k[i - 1] - 1.0;
    if (gap > 0.5)
    {
      missing += gap;
      s.bursts += 1.0;
    }
  }
  const double expected = k[n - 1] + 1.0;
  s.lost_fraction = missing / expected;
  s.mean_burst = s.bursts > 0 ? missing / s.bursts : 0.0;
  return s;
}

Recording sliceFraction(const Recording& recording, double from, double to)
{
  Recording out;
  out.rate = recording.rate;
  out.has_orientation = recording.has_orientation;
  out.has_temperature = recording.has_temperature;
  out.source = recording.source;
  const std::size_t n = recording.size();
  if (n == 0)
  {
    out.data.resize(0, kChannels);
    return out;
  }
  const double t0 = recording.stamp.front();
  const double span = recording.stamp.back() - t0 + (recording.rate > 0 ? 1.0 / recording.rate : 0.0);
  std::size_t i0 = n, i1 = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double f = (recording.stamp[i] - t0) / span;
    if (f >= from && f < to)
    {
      i0 = std::min(i0, i);
      i1 = std::max(i1, i + 1);
    }
  }
  if (i0 >= i1)
  {
    out.data.resize(0, kChannels);
    return out;
  }
  out.stamp.assign(recording.stamp.begin() + i0, recording.stamp.begin() + i1);
  out.data = recording.data.middleRows(i0, i1 - i0);
  if (recording.has_orientation)
  {
    out.orientation.assign(recording.orientation.begin() + i0, recording.orientation.begin() + i1);
  }
  if (recording.has_temperature)
  {
    out.temperature.assign(recording.temperature.begin() + i0, recording.temperature.begin() + i1);
  }
  return out;
}

namespace
{
/// What of a truth the sensor effects read (sim::Simulator::next(const Truth&, Sample*)), kept
/// compact while a motion is shared.
struct SensorTruth
{
  Eigen::Quaterniond attitude;
  Eigen::Vector3d acceleration;
  Eigen::Vector3d angular_rate;
  Eigen::Vector3d angular_acceleration;
};

/// The recording of the samples `next(Sample*)` produces until it returns false (`count` of them
/// at most), dropped samples removed, with the truth kept when asked.
template <class Next>
Recording record(const sim::Scenario& scenario, std::uint64_t seed, std::int64_t count, bool keep_truth, Next next)
{
  Recording r;
  r.rate = scenario.rate;
  r.source = "sim seed " + std::to_string(seed);
  r.stamp.reserve(count);
  r.data.resize(count, kChannels);
  r.has_orientation = true;
  r.orientation.reserve(count);
  r.has_temperature = scenario.temperature.enabled;
  sim::Sample s;
  std::int64_t k = 0;
  while (next(&s))
  {
    if (s.dropped)
    {
      continue;
    }
    r.stamp.push_back(s.stamp);
    r.data.row(k).head<3>() = s.accel.transpose();
    r.data.row(k).tail<3>() = s.gyro.transpose();
    r.orientation.push_back(s.orientation);
    if (keep_truth)
    {
      const sim::OdometryState odo = sim::truthOdometry(s.truth).total;
      r.truth.stamp.push_back(s.t);  // as ground_truth/odometry is stamped
      r.truth.position.push_back(odo.position);
      r.truth.orientation.push_back(odo.orientation);
      r.truth.velocity.push_back(odo.linear_velocity);
      r.truth.angular_velocity.push_back(odo.angular_velocity);
      r.truth.has_twist = true;
    }
    if (r.has_temperature)
    {
      r.temperature.push_back(s.temperature);
    }
    ++k;
  }
  r.data.conservativeResize(k, kChannels);
  return r;
}
}  // namespace

Recording simulateRecording(const sim::Scenario& scenario, std::uint64_t seed, bool keep_truth)
{
  sim::Simulator simulator(scenario, seed,
                           keep_truth ? sim::ShipMotion::Outputs::kAll : sim::ShipMotion::Outputs::kSensor);
  return record(scenario, seed, simulator.sampleCount(), keep_truth,
                [&simulator](sim::Sample* s) { return simulator.next(s); });
}

std::vector<std::string> simulateVariants(const std::vector<sim::Scenario>& scenarios, std::uint64_t seed,
                                          const std::function<void(int, Recording&)>& use)
{
  const int n = static_cast<int>(scenarios.size());
  std::vector<std::string> errors(n);
  std::vector<std::unique_ptr<sim::Simulator>> simulators(n);
  for (int v = 0; v < n; ++v)
  {
    try
    {
      simulators[v] = std::make_unique<sim::Simulator>(scenarios[v], seed, sim::ShipMotion::Outputs::kSensor);
    }
    catch (const std::exception& e)
    {
      errors[v] = e.what();
    }
  }
  // The first variant that can be simulated evaluates the motion and keeps it for the others.
  std::vector<SensorTruth> motion;
  bool evaluated = false;
  for (int v = 0; v < n; ++v)
  {
    if (!simulators[v])
    {
      continue;
    }
    sim::Simulator& simulator = *simulators[v];
    const std::int64_t count = simulator.sampleCount();
    Recording r;
    if (!evaluated)
    {
      motion.reserve(count);
      r = record(scenarios[v], seed, count, false, [&](sim::Sample* s) {
        if (!simulator.next(s))
          return false;
        motion.push_back(
            { s->truth.attitude, s->truth.acceleration, s->truth.angular_rate, s->truth.angular_acceleration });
        return true;
      });
      evaluated = true;
    }
    else
    {
      if (count != static_cast<std::int64_t>(motion.size()))
      {
        throw std::invalid_argument("simulateVariants: the scenarios differ in more than their effects");
      }
      std::size_t k = 0;
      sim::Truth truth;
      r = record(scenarios[v], seed, count, false, [&](sim::Sample* s) {
        if (k >= motion.size())
          return false;
        const SensorTruth& m = motion[k++];
        truth.attitude = m.attitude;
        truth.acceleration = m.acceleration;
        truth.angular_rate = m.angular_rate;
        truth.angular_acceleration = m.angular_acceleration;
        return simulator.next(truth, s);
      });
    }
    simulators[v].reset();
    use(v, r);
  }
  return errors;
}

sim::Scenario matchScenario(const sim::Scenario& scenario, const Recording& real)
{
  sim::Scenario s = scenario;
  const double rate = real.rate > 0 ? real.rate : estimateRate(real);
  if (rate > 0.0)
  {
    s.rate = rate;
  }
  if (real.size() > 1)
  {
    s.duration = real.stamp.back() - real.stamp.front() + 1.0 / s.rate;
    s.start_time = std::max(real.stamp.front(), 1e-3);
  }
  return s;
}
}  // namespace periodic_bias_compensation::gap
