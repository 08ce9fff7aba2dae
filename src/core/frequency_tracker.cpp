#include "periodic_bias_compensation/core/frequency_tracker.h"

#include "real_fft.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "periodic_bias_compensation/common/numeric.h"

namespace periodic_bias_compensation
{
struct FrequencyTracker::Plan
{
  explicit Plan(int n) : fft(n)
  {
  }
  RealFft fft;
  std::vector<double> power;
  std::vector<double> band_power;
  std::vector<double> window;  ///< Hann window for `window_length` samples
  int window_length = 0;
  double window_sum = 0.0;
};

FrequencyTracker::FrequencyTracker(int window_samples, double sample_rate, int decimation, bool background)
  : n_(decimation >= 1 ? window_samples / decimation : 0), rate_(sample_rate / decimation), decimation_(decimation)
{
  if (decimation < 1)
    throw std::invalid_argument("FrequencyTracker: decimation must be >= 1");
  if (n_ < 16)
    throw std::invalid_argument("FrequencyTracker: window must hold at least 16 samples after decimation");
  if (!(sample_rate > 0.0) || !std::isfinite(sample_rate))
    throw std::invalid_argument("FrequencyTracker: sample rate must be positive");
  moving_.assign(decimation_, 0.0);
  ring_ = std::make_shared<Ring>();
  ring_->values.assign(2 * static_cast<std::size_t>(n_), 0.0);
  ring_->times.assign(2 * static_cast<std::size_t>(n_), 0.0);
  fft_size_ = fastFftSize(n_);
  background_ = background;
  if (!background)
  {
    plan_ = std::make_unique<Plan>(fft_size_);
    plan_->power.resize(fft_size_ / 2 + 1);
    return;
  }
  auto planned = std::make_shared<std::promise<std::unique_ptr<Plan>>>();
  planning_ = planned->get_future();
  planInBackground([planned, size = fft_size_] {
    auto plan = std::make_unique<Plan>(size);
    plan->power.resize(size / 2 + 1);
    planned->set_value(std::move(plan));
  });
}

FrequencyTracker::~FrequencyTracker()
{
  if (!background_)
    return;
  // After the plan's own task: the plan, made or taken, is dropped on the planning thread (or on
  // the design thread by a search still under way there, which holds it too).
  auto plan = std::make_shared<std::shared_ptr<Plan>>(std::move(plan_));
  auto pending = std::make_shared<std::future<std::unique_ptr<Plan>>>(std::move(planning_));
  planInBackground([plan = std::move(plan), pending = std::move(pending)] {
    if (pending->valid())
      pending->get();
  });
}

FrequencyTracker::Plan& FrequencyTracker::plan()
{
  if (!plan_)
    plan_ = planning_.get();
  return *plan_;
}

void FrequencyTracker::push(double value)
{
  push(value, inputs_ > 0 ? last_time_ + 1.0 / sampleRate() : 0.0);
}

void FrequencyTracker::push(double value, double t)
{
  last_time_ = t;
  ++inputs_;
  if (decimation_ == 1)
    store(value, t);
  else
    decimate(value, t);
}

void FrequencyTracker::store(double value, double t)
{
  // A search task reads the n_ slots before the head it started at: the n_ after it are free.
  if (searching_.valid() && ++stores_since_search_ > n_)
    finishSearch();
  ring_->times[head_] = t;
  ring_->values[head_] = value;
  head_ = (head_ + 1) % static_cast<int>(ring_->values.size());
  ++count_;
}

void FrequencyTracker::decimate(double value, double t)
{
  const int m = decimation_;
  moving_sum_ += value - moving_[moving_head_];
  moving_[moving_head_] = value;
  if (++moving_head_ == m)
  {
    moving_head_ = 0;
    // Exact again once per M inputs: no rounding drift over weeks of samples.
    moving_sum_ = 0.0;
    for (double v : moving_)
      moving_sum_ += v;
  }
  if (inputs_ < m)
    return;  // the moving average is not full yet
  block_sum_ += moving_sum_;
  block_time_ += t;
  if (++block_count_ < m)
    return;
  store(block_sum_ / (static_cast<double>(m) * m), block_time_ / m);
  block_sum_ = 0.0;
  block_time_ = 0.0;
  block_count_ = 0;
}

void FrequencyTracker::clear()
{
  // The head stays: a search task under way may still read the slots behind it.
  count_ = 0;
  std::fill(moving_.begin(), moving_.end(), 0.0);
  moving_head_ = 0;
  moving_sum_ = block_sum_ = block_time_ = 0.0;
  block_count_ = 0;
  inputs_ = 0;
}

bool FrequencyTracker::full() const
{
  return count_ >= n_;
}

int FrequencyTracker::samples() const
{
  return static_cast<int>(std::min<long>(count_, n_)) * decimation_;
}

void FrequencyTracker::finishSearch()
{
  if (searching_.valid())
    searching_.wait();
  searching_ = {};
}

FrequencyEstimate FrequencyTracker::analyse(double f_min, double f_max, double min_peak_ratio, int recent_samples)
{
  finishSearch();
  return analyseHeld(held(), shape(), plan(), f_min, f_max, min_peak_ratio, recent_samples);
}

FrequencyEstimate FrequencyTracker::analyseHeld(const Held& held, const Shape& shape, Plan& planned, double f_min,
                                                double f_max, double min_peak_ratio, int recent_samples)
{
  FrequencyEstimate estimate;
  const int n = held.length;
  int available = static_cast<int>(std::min<long>(held.count, held.window));
  if (recent_samples > 0)
    available = std::min(available, recent_samples / shape.decimation);
  if (available < 16)
    return estimate;

  // The newest `available` samples, oldest first: at most two contiguous pieces of the ring
  // (no index arithmetic per sample).
  const int first = (held.head - available + n) % n;
  const int first_length = std::min(available, n - first);
  const double* pieces[2] = { held.values + first, held.values };
  const int lengths[2] = { first_length, available - first_length };

  // Mean removed, Hann-windowed, zero-padded to the FFT size.
  double mean = 0.0;
  for (int p = 0; p < 2; ++p)
    for (int i = 0; i < lengths[p]; ++i)
      mean += pieces[p][i];
  mean /= available;
  double variance = 0.0;
  for (int p = 0; p < 2; ++p)
    for (int i = 0; i < lengths[p]; ++i)
    {
      const double d = pieces[p][i] - mean;
      variance += d * d;
    }
  // A (numerically) constant signal has no period, whatever its rounding noise looks like.
  if (variance / available <= 1e-18 * (1.0 + mean * mean))
    return estimate;
  if (planned.window_length != available)
  {
    // cos(2 pi (i + 1/2) / N) by rotation: the window is rebuilt at every hop while the ring
    // fills, and N cos() calls would cost more than the FFT.
    planned.window.resize(available);
    planned.window_sum = 0.0;
    const double step = 2.0 * M_PI / available;
    const double cos_step = std::cos(step), sin_step = std::sin(step);
    double c = std::cos(0.5 * step), s = std::sin(0.5 * step);
    for (int i = 0; i < available; ++i)
    {
      planned.window[i] = 0.5 - 0.5 * c;
      planned.window_sum += planned.window[i];
      const double next_c = c * cos_step - s * sin_step;
      s = s * cos_step + c * sin_step;
      c = next_c;
    }
    planned.window_length = available;
  }
  const double window_sum = planned.window_sum;
  const double* window = planned.window.data();
  double* in = planned.fft.in;
  for (int p = 0; p < 2; ++p)
  {
    for (int i = 0; i < lengths[p]; ++i)
      in[i] = window[i] * (pieces[p][i] - mean);
    in += lengths[p];
    window += lengths[p];
  }
  std::fill(planned.fft.in + available, planned.fft.in + shape.fft_size, 0.0);
  planned.fft.execute();

  const double elapsed = held.times[(held.head - 1 + n) % n] - held.times[first];
  const double rate = elapsed > 0.0 ? (available - 1) / elapsed : shape.rate;
  const int bins = shape.fft_size / 2 + 1;
  const double df = rate / shape.fft_size;

  // Search band: never DC (bin 0) nor Nyquist, and a period must fit 3 times in the data.
  const double span = available / rate;
  const double f_lo = std::max({ f_min, 3.0 / span, df });
  const int k_lo = std::max(1, static_cast<int>(std::ceil(f_lo / df)));
  const int k_hi = std::min(bins - 2, static_cast<int>(std::floor(f_max / df)));
  if (k_hi - k_lo < 2)
    return estimate;
  // Power only where it is read: the band and one bin either side (interpolation).
  for (int k = k_lo - 1; k <= k_hi + 1; ++k)
    planned.power[k] = planned.fft.power(k);

  int k_peak = k_lo;
  for (int k = k_lo; k <= k_hi; ++k)
    if (planned.power[k] > planned.power[k_peak])
      k_peak = k;

  auto& band = planned.band_power;
  band.assign(planned.power.begin() + k_lo, planned.power.begin() + k_hi + 1);
  const double median = upperMedian(band.begin(), band.end());
  estimate.peak_ratio = median > 0.0 ? planned.power[k_peak] / median : 0.0;

  // Gaussian (log-parabolic) interpolation: nearly unbiased for a Hann-windowed sinusoid.
  double offset = 0.0;
  if (k_peak > 0 && k_peak < bins - 1)
  {
    const double a = std::log(std::max(planned.power[k_peak - 1], 1e-300));
    const double b = std::log(std::max(planned.power[k_peak], 1e-300));
    const double c = std::log(std::max(planned.power[k_peak + 1], 1e-300));
    const double denominator = a - 2.0 * b + c;
    if (denominator < 0.0)
      offset = std::clamp(0.5 * (a - c) / denominator, -0.5, 0.5);
  }
  estimate.frequency = (k_peak + offset) * df;
  // Amplitude of a sinusoid from the peak of a Hann window (coherent gain = window_sum).
  estimate.amplitude = 2.0 * std::sqrt(planned.power[k_peak]) / window_sum;
  // A band-edge bin lower than its neighbour outside the band is the skirt of a line below the
  // band (a period that does not fit three times in the data yet), not a peak.
  const bool local_maximum =
      planned.power[k_peak] >= planned.power[k_peak - 1] && planned.power[k_peak] >= planned.power[k_peak + 1];
  estimate.locked = local_maximum && estimate.peak_ratio >= min_peak_ratio && estimate.frequency >= f_lo &&
                    estimate.frequency <= f_max;
  return estimate;
}

FrequencyEstimate FrequencyTracker::analyseFreshest(double f_min, double f_max, double min_peak_ratio,
                                                    int recent_samples, int* span_samples)
{
  finishSearch();
  const FrequencySearch found = searchHeld(held(), shape(), plan(), f_min, f_max, min_peak_ratio, recent_samples, true);
  *span_samples = found.span_samples;
  return found.estimate;
}

FrequencySearch FrequencyTracker::searchHeld(const Held& held, const Shape& shape, Plan& planned, double f_min,
                                             double f_max, double min_peak_ratio, int recent_samples, bool freshest)
{
  FrequencySearch found;
  found.samples = static_cast<int>(std::min<long>(held.count, held.window)) * shape.decimation;
  found.full = held.count >= held.window;
  if (!freshest)
  {
    found.estimate = analyseHeld(held, shape, planned, f_min, f_max, min_peak_ratio, recent_samples);
    found.span_samples = std::min(found.samples, recent_samples);
    return found;
  }
  found.estimate = analyseHeld(held, shape, planned, f_min, f_max, min_peak_ratio, 0);
  found.span_samples = found.samples;
  const double recent_span = static_cast<double>(recent_samples) / (shape.rate * shape.decimation);
  if (found.estimate.locked && found.samples > recent_samples && found.estimate.frequency >= 3.0 / recent_span)
  {
    const FrequencyEstimate fresh = analyseHeld(held, shape, planned, f_min, f_max, min_peak_ratio, recent_samples);
    if (fresh.locked && std::abs(fresh.frequency - found.estimate.frequency) <= 0.2 * found.estimate.frequency)
    {
      found.estimate = fresh;
      found.span_samples = recent_samples / shape.decimation * shape.decimation;
    }
  }
  return found;
}

std::function<FrequencySearch()> FrequencyTracker::searchTask(double f_min, double f_max, double min_peak_ratio,
                                                              int recent_samples, bool freshest)
{
  finishSearch();  // the transform is the tracker's: one search at a time
  plan();
  auto done = std::make_shared<std::promise<void>>();
  searching_ = done->get_future().share();
  stores_since_search_ = 0;
  return [ring = ring_, plan = plan_, done, held = held(), shape = shape(), f_min, f_max, min_peak_ratio,
          recent_samples, freshest] {
    const FrequencySearch found =
        searchHeld(held, shape, *plan, f_min, f_max, min_peak_ratio, recent_samples, freshest);
    done->set_value();
    return found;
  };
}

}  // namespace periodic_bias_compensation
