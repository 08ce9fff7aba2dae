#include "periodic_bias_compensation/core/frequency_tracker.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace periodic_bias_compensation
{
namespace
{
// FFTW's planner is not thread-safe; execution of an existing plan is.
std::mutex& plannerMutex()
{
  static std::mutex mutex;
  return mutex;
}
}  // namespace

struct FrequencyTracker::Plan
{
  explicit Plan(int n) : n(n)
  {
    in = fftw_alloc_real(n);
    out = fftw_alloc_complex(n / 2 + 1);
    std::lock_guard<std::mutex> lock(plannerMutex());
    plan = fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
  }
  ~Plan()
  {
    std::lock_guard<std::mutex> lock(plannerMutex());
    fftw_destroy_plan(plan);
    fftw_free(in);
    fftw_free(out);
  }
  int n;
  double* in;
  fftw_complex* out;
  fftw_plan plan;
  std::vector<double> power;
  std::vector<double> band_power;
};

FrequencyTracker::FrequencyTracker(int window_samples, double sample_rate)
  : n_(window_samples), rate_(sample_rate)
{
  if (window_samples < 16)
    throw std::invalid_argument("FrequencyTracker: window must hold at least 16 samples");
  if (!(sample_rate > 0.0) || !std::isfinite(sample_rate))
    throw std::invalid_argument("FrequencyTracker: sample rate must be positive");
  ring_.assign(n_, 0.0);
  times_.assign(n_, 0.0);
  plan_ = std::make_unique<Plan>(n_);
  plan_->power.resize(n_ / 2 + 1);
}

FrequencyTracker::~FrequencyTracker() = default;

void FrequencyTracker::push(double value)
{
  push(value, count_ > 0 ? times_[(head_ - 1 + n_) % n_] + 1.0 / rate_ : 0.0);
}

void FrequencyTracker::push(double value, double t)
{
  times_[head_] = t;
  ring_[head_] = value;
  head_ = (head_ + 1) % n_;
  ++count_;
}

void FrequencyTracker::clear()
{
  std::fill(ring_.begin(), ring_.end(), 0.0);
  head_ = 0;
  count_ = 0;
}

bool FrequencyTracker::full() const
{
  return count_ >= n_;
}

int FrequencyTracker::samples() const
{
  return static_cast<int>(std::min<long>(count_, n_));
}

FrequencyEstimate FrequencyTracker::analyse(double f_min, double f_max, double min_peak_ratio)
{
  FrequencyEstimate estimate;
  const int available = static_cast<int>(std::min<long>(count_, n_));
  if (available < 16)
    return estimate;

  // The newest `available` samples, mean removed, Hann-windowed, zero-padded to n_.
  double mean = 0.0;
  for (int i = 0; i < available; ++i)
    mean += ring_[(head_ - available + i + n_) % n_];
  mean /= available;
  double variance = 0.0;
  for (int i = 0; i < available; ++i)
  {
    const double d = ring_[(head_ - available + i + n_) % n_] - mean;
    variance += d * d;
  }
  // A (numerically) constant signal has no period, whatever its rounding noise looks like.
  if (variance / available <= 1e-18 * (1.0 + mean * mean))
    return estimate;
  double window_sum = 0.0;
  for (int i = 0; i < n_; ++i)
  {
    if (i < available)
    {
      const double w = 0.5 - 0.5 * std::cos(2.0 * M_PI * (i + 0.5) / available);
      plan_->in[i] = w * (ring_[(head_ - available + i + n_) % n_] - mean);
      window_sum += w;
    }
    else
    {
      plan_->in[i] = 0.0;
    }
  }
  fftw_execute(plan_->plan);

  const double elapsed = times_[(head_ - 1 + n_) % n_] - times_[(head_ - available + n_) % n_];
  const double rate = elapsed > 0.0 ? (available - 1) / elapsed : rate_;
  const int bins = n_ / 2 + 1;
  const double df = rate / n_;
  for (int k = 0; k < bins; ++k)
    plan_->power[k] = plan_->out[k][0] * plan_->out[k][0] + plan_->out[k][1] * plan_->out[k][1];

  // Search band: never DC (bin 0) nor Nyquist, and a period must fit 3 times in the data.
  const double span = available / rate;
  const double f_lo = std::max({ f_min, 3.0 / span, df });
  const int k_lo = std::max(1, static_cast<int>(std::ceil(f_lo / df)));
  const int k_hi = std::min(bins - 2, static_cast<int>(std::floor(f_max / df)));
  if (k_hi - k_lo < 2)
    return estimate;

  int k_peak = k_lo;
  for (int k = k_lo; k <= k_hi; ++k)
    if (plan_->power[k] > plan_->power[k_peak])
      k_peak = k;

  auto& band = plan_->band_power;
  band.assign(plan_->power.begin() + k_lo, plan_->power.begin() + k_hi + 1);
  std::nth_element(band.begin(), band.begin() + band.size() / 2, band.end());
  const double median = band[band.size() / 2];
  estimate.peak_ratio = median > 0.0 ? plan_->power[k_peak] / median : 0.0;

  // Gaussian (log-parabolic) interpolation: nearly unbiased for a Hann-windowed sinusoid.
  double offset = 0.0;
  if (k_peak > 0 && k_peak < bins - 1)
  {
    const double a = std::log(std::max(plan_->power[k_peak - 1], 1e-300));
    const double b = std::log(std::max(plan_->power[k_peak], 1e-300));
    const double c = std::log(std::max(plan_->power[k_peak + 1], 1e-300));
    const double denominator = a - 2.0 * b + c;
    if (denominator < 0.0)
      offset = std::clamp(0.5 * (a - c) / denominator, -0.5, 0.5);
  }
  estimate.frequency = (k_peak + offset) * df;
  // Amplitude of a sinusoid from the peak of a Hann window (coherent gain = window_sum).
  estimate.amplitude = 2.0 * std::sqrt(plan_->power[k_peak]) / window_sum;
  estimate.locked = estimate.peak_ratio >= min_peak_ratio && estimate.frequency >= f_lo &&
                    estimate.frequency <= f_max;
  return estimate;
}

}  // namespace periodic_bias_compensation
