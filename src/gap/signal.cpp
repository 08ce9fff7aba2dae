// Signal processing of the gap diagnosis: Welch PSD (FFTW3), Allan deviation, lattices,
// flat tops, stamp statistics; recordings from the simulator.
#include <fftw3.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/gap/gap.h"
#include "periodic_bias_compensation/sim/simulator.h"

namespace periodic_bias_compensation::gap
{
namespace
{
std::mutex& fftwMutex()
{
  static std::mutex m;
  return m;
}

/// FFTW real-to-complex plan for one length (planning is not thread-safe: under a mutex).
class RealFft
{
public:
  explicit RealFft(int n) : n_(n)
  {
    in_ = fftw_alloc_real(n);
    out_ = fftw_alloc_complex(n / 2 + 1);
    std::lock_guard<std::mutex> lock(fftwMutex());
    plan_ = fftw_plan_dft_r2c_1d(n, in_, out_, FFTW_ESTIMATE);
  }
  ~RealFft()
  {
    std::lock_guard<std::mutex> lock(fftwMutex());
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

double estimateRate(const Recording& recording)
{
  const std::size_t n = recording.size();
  if (n < 2)
  {
    return 0.0;
  }
  std::vector<double> dt;
  dt.reserve(n - 1);
  for (std::size_t i = 1; i < n; ++i)
  {
    dt.push_back(recording.stamp[i] - recording.stamp[i - 1]);
  }
  const double med = median(std::move(dt));
  return med > 0.0 ? 1.0 / med : 0.0;
}

StampStats stampStats(const std::vector<double>& stamp, double rate)
{
  StampStats s;
  const std::size_t n = stamp.size();
  if (n < 3 || rate <= 0.0)
  {
    return s;
  }
  std::vector<double> k(n);
  double prev_k = -1.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    k[i] = std::round((stamp[i] - stamp[0]) * rate);
    if (k[i] <= prev_k)
    {
      k[i] = prev_k + 1.0;  // jitter or backwards: keep the index increasing
    }
    prev_k = k[i];
    if (i > 0 && stamp[i] < stamp[i - 1])
    {
      s.backwards += 1.0;
    }
  }
  // Straight line stamp = a + b k.
  double sk = 0, st = 0, skk = 0, skt = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    sk += k[i];
    st += stamp[i];
    skk += k[i] * k[i];
    skt += k[i] * stamp[i];
  }
  const double dn = static_cast<double>(n);
  const double b = (dn * skt - sk * st) / std::max(dn * skk - sk * sk, 1e-300);
  const double a = (st - b * sk) / dn;
  s.rate = b > 0.0 ? 1.0 / b : 0.0;
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    r[i] = stamp[i] - (a + b * k[i]);
  }
  std::vector<double> ar = r;
  const double med = upperMedian(ar.begin(), ar.end());
  for (double& v : ar)
  {
    v = std::abs(v - med);
  }
  s.jitter = 1.4826 * upperMedian(ar.begin(), ar.end());
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

Recording simulateRecording(const sim::Scenario& scenario, std::uint64_t seed, bool keep_truth)
{
  sim::Simulator simulator(scenario, seed);
  Recording r;
  r.rate = scenario.rate;
  r.source = "sim seed " + std::to_string(seed);
  const std::int64_t n = simulator.sampleCount();
  r.stamp.reserve(n);
  r.data.resize(n, kChannels);
  r.has_orientation = true;
  r.orientation.reserve(n);
  r.has_temperature = scenario.temperature.enabled;
  sim::Sample s;
  std::int64_t k = 0;
  while (simulator.next(&s))
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
