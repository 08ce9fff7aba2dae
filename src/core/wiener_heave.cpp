#include "periodic_bias_compensation/core/wiener_heave.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "real_fft.h"

namespace periodic_bias_compensation
{
namespace
{
/// Solves T x = b for the symmetric Toeplitz T with first column t (Levinson recursion, O(n^2)).
/// Returns false when T is not positive definite to working precision.
bool solveToeplitz(const std::vector<double>& t, const std::vector<double>& b, std::vector<double>* x)
{
  const int n = static_cast<int>(t.size());
  if (n == 0 || !(t[0] > 0.0))
    return false;
  std::vector<double> forward(n, 0.0), next(n, 0.0);
  x->assign(n, 0.0);
  forward[0] = 1.0 / t[0];
  (*x)[0] = b[0] / t[0];
  for (int m = 1; m < n; ++m)
  {
    // Error of the forward vector extended by a zero; the backward vector is its reverse.
    double e = 0.0;
    for (int i = 0; i < m; ++i)
      e += t[m - i] * forward[i];
    const double denominator = 1.0 - e * e;
    if (!(denominator > 1e-12))
      return false;
    for (int i = 0; i <= m; ++i)
    {
      const double f = i < m ? forward[i] : 0.0;
      const double g = i > 0 ? forward[m - i] : 0.0;
      next[i] = (f - e * g) / denominator;
    }
    std::copy(next.begin(), next.begin() + m + 1, forward.begin());
    double ex = 0.0;
    for (int i = 0; i < m; ++i)
      ex += t[m - i] * (*x)[i];
    const double correction = b[m] - ex;
    // Backward vector: forward reversed.
    for (int i = 0; i <= m; ++i)
      (*x)[i] += correction * forward[m - i];
  }
  return true;
}
}  // namespace

WienerHeave::WienerHeave(double min_frequency, bool vertical) : min_frequency_(min_frequency), vertical_(vertical)
{
  setMinFrequency(min_frequency);
}

void WienerHeave::setMinFrequency(double min_frequency)
{
  if (!(min_frequency > 0.0) || !std::isfinite(min_frequency))
    throw std::invalid_argument("WienerHeave: min_frequency must be finite and > 0");
  min_frequency_ = min_frequency;
  reset();
}

void WienerHeave::reset()
{
  dt_ = sized_dt_ = 0.0;
  decimation_ = 0;
  first_.clear();
  second_.clear();
  first_sum_ = second_sum_ = 0.0;
  samples_ = 0;
  history_.clear();
  ring_length_ = 0;
  newest_ = 0;
  decimated_.clear();
  since_design_ = 0.0;
  since_manoeuvre_ = std::numeric_limits<double>::infinity();
  current_.reset();
  previous_.reset();
  fade_ = 1.0;
  peak_frequency_ = 0.0;
  stale_ = false;
}

void WienerHeave::restartRecord()
{
  decimated_.clear();
  since_design_ = 0.0;
  stale_ = current_ != nullptr;
}

WienerHeaveOutput WienerHeave::update(double a, double period, double noise_density_squared)
{
  WienerHeaveOutput out;
  // Periods outside kMinPeriod..kMaxPeriod (not known yet, a glitch, not an IMU) would size the
  // buffers absurdly: never taken.
  if (!std::isfinite(a) || !(period >= kMinPeriod && period <= kMaxPeriod))
    return out;
  if (decimation_ > 0 && std::abs(period - sized_dt_) > kPeriodChange * sized_dt_)
    reset();  // a new rate: the buffers and the design are the old one's
  dt_ = period;
  if (decimation_ == 0)
  {
    sized_dt_ = period;
    decimation_ = std::max(1, static_cast<int>(std::lround(kDesignPeriod / dt_)));
    first_.assign(decimation_, 0.0);
    second_.assign(decimation_, 0.0);
    ring_length_ = static_cast<int>(std::ceil(kMaxSpan / (decimation_ * dt_)));
    history_.assign(static_cast<size_t>(ring_length_) * decimation_, 0.0);
  }
  // Two moving averages (running sums over circular buffers of decimation_ values).
  const int slot = static_cast<int>(samples_ % decimation_);
  first_sum_ += a - first_[slot];
  first_[slot] = a;
  const double once = first_sum_ / decimation_;
  second_sum_ += once - second_[slot];
  second_[slot] = once;
  const double low = second_sum_ / decimation_;
  // Sample m goes to ring m mod D, place (m / D) mod ring_length_.
  newest_ = static_cast<int>(slot * ring_length_ + (samples_ / decimation_) % ring_length_);
  history_[newest_] = low;
  ++samples_;
  if (samples_ < 2 * decimation_)
    return out;  // the averages are not full yet
  if (samples_ % decimation_ == 0)
  {
    decimated_.push_back(low);
    const size_t most = static_cast<size_t>(kDesignWindow / (decimation_ * dt_));
    if (decimated_.size() > most)
      decimated_.erase(decimated_.begin(), decimated_.begin() + (decimated_.size() - most));
  }
  since_design_ += dt_;
  since_manoeuvre_ += dt_;
  const double recorded = decimated_.size() * decimation_ * dt_;
  const double interval = recorded < kEarlyRecord ? kEarlyRedesignInterval : kRedesignInterval;
  const double first = current_ ? kRestartDesign : kFirstDesign;
  if ((current_ && !stale_ ? since_design_ >= interval : recorded >= first) &&
      static_cast<int>(decimated_.size()) >= kMinSegment)
  {
    design(noise_density_squared);
    since_design_ = 0.0;
  }
  if (!current_)
    return out;
  apply(*current_, &out.position, &out.velocity);
  out.error_variance = current_->error_variance;
  out.velocity_error_variance = current_->velocity_error_variance;
  out.wave_variance = current_->wave_variance;
  if (previous_)
  {
    fade_ = std::min(1.0, fade_ + dt_ / kDesignFade);
    double x_old = 0.0, v_old = 0.0;
    apply(*previous_, &x_old, &v_old);
    out.position = fade_ * out.position + (1.0 - fade_) * x_old;
    out.velocity = fade_ * out.velocity + (1.0 - fade_) * v_old;
    if (fade_ >= 1.0)
      previous_.reset();
  }
  out.valid = !stale_;
  return out;
}

void WienerHeave::apply(const Design& d, double* x, double* v) const
{
  // The values D samples apart ending at the newest lie next to each other in its ring,
  // newest last: walked backwards from the newest to the ring's start, then from its end.
  const double* ring = history_.data() + (newest_ / ring_length_) * ring_length_;
  const int taps = static_cast<int>(d.position.size());
  const int place = newest_ % ring_length_;
  const int before_wrap = std::min(taps, place + 1);
  // Four partial sums each: four independent chains of additions instead of one.
  double px[4] = { 0.0, 0.0, 0.0, 0.0 }, pv[4] = { 0.0, 0.0, 0.0, 0.0 };
  const double* position = d.position.data();
  const double* velocity = d.velocity.data();
  auto accumulate = [&](const double* newest, int first_tap, int end_tap) {
    const double* value = newest + first_tap;  // value[-k]: tap k's input
    int k = first_tap;
    for (; k + 4 <= end_tap; k += 4)
      for (int j = 0; j < 4; ++j)
      {
        const double centred = value[-(k + j)] - d.mean;
        px[j] += position[k + j] * centred;
        pv[j] += velocity[k + j] * centred;
      }
    for (; k < end_tap; ++k)
    {
      const double centred = value[-k] - d.mean;
      px[0] += position[k] * centred;
      pv[0] += velocity[k] * centred;
    }
  };
  accumulate(ring + place, 0, before_wrap);
  accumulate(ring + ring_length_ - 1, before_wrap, taps);
  *x = (px[0] + px[1]) + (px[2] + px[3]);
  *v = (pv[0] + pv[1]) + (pv[2] + pv[3]);
}

std::vector<double> WienerHeave::welch(int segment, double mean, std::vector<double>* response) const
{
  RealFft& fft = *transform_.fft;
  const int n = static_cast<int>(decimated_.size());
  const double fs = 1.0 / (decimation_ * dt_);
  const int bins = kDftSize / 2 + 1;
  std::vector<double> density(bins, 0.0);
  double window_power = 0.0;
  const std::vector<double> window = hannWindow(segment, &window_power);
  int segments = 0;
  for (int start = n - segment; start >= 0; start -= std::max(1, segment / 2), ++segments)
  {
    for (int i = 0; i < segment; ++i)
      fft.in[i] = window[i] * (decimated_[start + i] - mean);
    std::fill(fft.in + segment, fft.in + kDftSize, 0.0);
    fft.execute();
    for (int k = 0; k < bins; ++k)
      density[k] += fft.power(k);
  }
  for (double& d : density)
    d /= segments * window_power * fs;
  // The window spreads every line over neighbouring bins (over +-2 bins of a segment in its main
  // lobe). Its response, relative to its peak:
  for (int i = 0; i < kDftSize; ++i)
    fft.in[i] = i < segment ? window[i] : 0.0;
  fft.execute();
  response->resize(bins);
  for (int k = 0; k < bins; ++k)
    (*response)[k] = fft.power(k) / fft.power(0);
  return density;
}

std::vector<double> WienerHeave::burg(int order, double mean) const
{
  // Forward and backward prediction errors; each stage's reflection coefficient minimises their
  // summed power (Burg), which keeps the model stable (|k| < 1).
  const int n = static_cast<int>(decimated_.size());
  std::vector<double> forward(n), backward(n), a(1, 1.0), previous;
  double power = 0.0;
  for (int i = 0; i < n; ++i)
  {
    forward[i] = backward[i] = decimated_[i] - mean;
    power += forward[i] * forward[i];
  }
  power /= n;
  for (int m = 1; m <= order; ++m)
  {
    double cross = 0.0, sum = 0.0;
    for (int i = m; i < n; ++i)
    {
      cross += forward[i] * backward[i - 1];
      sum += forward[i] * forward[i] + backward[i - 1] * backward[i - 1];
    }
    if (!(sum > 0.0))
      break;
    const double k = -2.0 * cross / sum;
    for (int i = n - 1; i >= m; --i)
    {
      const double f = forward[i];
      forward[i] = f + k * backward[i - 1];
      backward[i] = backward[i - 1] + k * f;
    }
    a.push_back(0.0);
    previous = a;
    for (int j = 1; j <= m; ++j)
      a[j] = previous[j] + k * previous[m - j];
    power *= 1.0 - k * k;
  }
  // Density power / (fs |A(f)|^2), A the prediction-error filter's response.
  RealFft& fft = *transform_.fft;
  std::fill(fft.in, fft.in + kDftSize, 0.0);
  std::copy(a.begin(), a.end(), fft.in);
  fft.execute();
  const double fs = 1.0 / (decimation_ * dt_);
  std::vector<double> density(kDftSize / 2 + 1);
  for (std::size_t k = 0; k < density.size(); ++k)
    density[k] = power / (fs * std::max(fft.power(static_cast<int>(k)), 1e-300));
  return density;
}

WienerHeave::Wave WienerHeave::wave(std::vector<double> density, const std::vector<double>& response,
                                    double noise_density_squared, Estimate kind) const
{
  const double fs = 1.0 / (decimation_ * dt_);
  const int bins = kDftSize / 2 + 1;

  // Wave acceleration per bin, less the white noise and, through a window, what a bin may owe to
  // the lines below min_frequency (bias wander, a manoeuvre: the largest lines of the spectrum).
  const double df = fs / kDftSize;
  const double floor = 0.5 * std::max(noise_density_squared, 0.0);
  const int below = std::min(bins, static_cast<int>(std::ceil(min_frequency_ / df)));
  // A short record's autoregressive model cannot tell a line below the band from the band's first
  // kEdgeResolution / T (T the record's length): the band starts that much higher.
  const double record = static_cast<double>(decimated_.size()) / fs;
  const int first = kind == Estimate::kShortBurg
                        ? std::min(bins, static_cast<int>(std::ceil((min_frequency_ + kEdgeResolution / record) / df)))
                        : below;
  Wave out;
  out.wave.assign(bins, 0.0);
  out.gain.assign(bins, 0.0);
  std::vector<double>& wave = out.wave;
  std::vector<double>& gain = out.gain;
  for (int k = 1; k < bins; ++k)
  {
    const double half = M_PI * k * df * dt_;
    const double ratio = std::sin(decimation_ * half) / (decimation_ * std::sin(half));
    gain[k] = ratio * ratio;
    // An autoregressive model of a record holds lines with next to no power between them; the
    // sensor's white noise is there all the same (and keeps the normal equations well posed).
    if (kind != Estimate::kWelch)
      density[k] = std::max(density[k], floor * gain[k] * gain[k]);
    if (k >= first && gain[k] > 1e-6)
    {
      double leak = 0.0;
      if (kind == Estimate::kWelch)
        for (int j = 0; j < below; ++j)
          leak += density[j] * response[k - j];
      wave[k] = std::max(0.0, density[k] - kNoiseMargin * (floor * gain[k] * gain[k] + leak)) / (gain[k] * gain[k]);
    }
  }
  const auto displacement = [&](int k) {
    const double omega = 2.0 * M_PI * k * df;
    return wave[k] / (omega * omega * omega * omega);
  };
  // On a short record, a displacement density that falls from the band's start is the skirt of a
  // line below it, not a sea: the band starts at the skirt's foot.
  if (kind == Estimate::kShortBurg)
  {
    int foot = first;
    while (foot + 1 < bins && displacement(foot) > 0.0 && displacement(foot + 1) <= displacement(foot))
      ++foot;
    if (foot > first)
      std::fill(wave.begin(), wave.begin() + foot, 0.0);
  }
  double peak = 0.0;
  for (int k = 1; k < bins; ++k)
  {
    const double f = k * df, omega = 2.0 * M_PI * f;
    out.displacement_variance += 2.0 * displacement(k) * df;
    out.velocity_variance += 2.0 * displacement(k) * omega * omega * df;
    if (displacement(k) > peak)
    {
      peak = displacement(k);
      out.peak_frequency = f;
    }
  }
  out.density = std::move(density);
  return out;
}

WienerHeave::Statistics WienerHeave::statistics(const Wave& w) const
{
  Statistics out;
  if (!(w.peak_frequency > 0.0))
    return out;  // no wave in the spectrum
  RealFft& fft = *transform_.fft;
  const double fs = 1.0 / (decimation_ * dt_);
  const int bins = kDftSize / 2 + 1;
  const double df = fs / kDftSize;
  const double span = std::clamp(kSpanPeriods / w.peak_frequency, kMinSpan, kMaxSpan);
  // No longer than the input held since reset() (less the low-pass's start): beyond it the FIR
  // would read the history's zeros, not the sea.
  const int held = static_cast<int>(samples_ / decimation_) - 2;
  const int taps =
      std::max(1, std::min({ static_cast<int>(std::lround(span * fs)), kDftSize / 2, held, ring_length_ }));

  // The cross-spectrum E[x a_d*] of displacement and low-passed acceleration; the low-pass's
  // response AA (two moving averages of D samples at dt).
  std::vector<std::complex<double>> cross(bins);
  for (int k = 1; k < bins; ++k)
  {
    const double f = k * df, omega = 2.0 * M_PI * f;
    const std::complex<double> aa = w.gain[k] * std::polar(1.0, -omega * (decimation_ - 1) * dt_);
    cross[k] = -std::conj(aa) * w.wave[k] / (omega * omega);
  }
  // Correlations at lags 0..taps-1: the inverse transforms of the (Hermitian) spectra, the
  // velocity's cross-spectrum j omega times the displacement's.
  const auto correlation = [&](auto spectrum) {
    for (int k = 0; k < bins; ++k)
    {
      const std::complex<double> value = spectrum(k);
      fft.out[k][0] = value.real();
      fft.out[k][1] = value.imag();
    }
    fft.inverse();
    return std::vector<double>(fft.in, fft.in + taps);
  };
  out.autocorrelation = correlation([&](int k) { return std::complex<double>(w.density[k] * df); });
  out.r_position = correlation([&](int k) { return cross[k] * df; });
  out.r_velocity = correlation([&](int k) { return std::complex<double>(0.0, 2.0 * M_PI * k * df) * cross[k] * df; });
  return out;
}

void WienerHeave::design(double noise_density_squared)
{
  if (!transform_.fft)
    transform_.fft = std::make_shared<RealFft>(kDftSize);
  const int n = static_cast<int>(decimated_.size());
  double mean = 0.0;
  for (double value : decimated_)
    mean += value;
  mean /= n;

  // Segments of kSegment once the record holds two; before that the whole record as one: on a
  // short record the resolution decides (a swell lies within the main lobe of short segments'
  // zero frequency), more than the variance that averaging segments removes. A long vertical
  // record takes Burg's estimate, which needs no window: no lobe spreads a slow bias line over
  // the band's edge. Horizontally a manoeuvre's lines are the largest, and Welch's window says
  // what the band owes them: a horizontal record takes Burg's estimate only while its window
  // holds no manoeuvre. A short vertical record whose window leaves its displacement peak
  // (or none) within kResolvedCycles cycles of zero frequency takes Burg's estimate too, of order
  // kShortOrder times its length: a swell a window cannot resolve yet (a line it resolves, Burg's
  // model of a short record splits and moves).
  Wave sea;
  const double record = n * decimation_ * dt_;
  if ((vertical_ || since_manoeuvre_ > record) && n >= 2 * kSegment)
    sea = wave(burg(kMaxOrder, mean), {}, noise_density_squared, Estimate::kBurg);
  else
  {
    std::vector<double> response;
    std::vector<double> density = welch(n < 2 * kSegment ? n : kSegment, mean, &response);
    sea = wave(std::move(density), response, noise_density_squared, Estimate::kWelch);
    if (vertical_ && sea.peak_frequency * record < kResolvedCycles)
      sea = wave(burg(std::min(kMaxOrder, static_cast<int>(kShortOrder * n)), mean), {}, noise_density_squared,
                 Estimate::kShortBurg);
  }
  const Statistics fit = statistics(sea);
  if (fit.autocorrelation.empty())
  {
    peak_frequency_ = 0.0;
    // No wave in the spectrum: no heave.
    auto none = std::make_shared<Design>();
    none->position.assign(1, 0.0);
    none->velocity.assign(1, 0.0);
    none->mean = mean;
    previous_ = std::move(current_);
    current_ = std::move(none);
    stale_ = false;
    fade_ = previous_ ? 0.0 : 1.0;
    return;
  }
  auto next = std::make_shared<Design>();
  if (!solveToeplitz(fit.autocorrelation, fit.r_position, &next->position) ||
      !solveToeplitz(fit.autocorrelation, fit.r_velocity, &next->velocity))
    return;  // keep the last design, and its peak
  peak_frequency_ = sea.peak_frequency;
  // The expected error E[(x - h a)^2] = var(x) - h r of taps solved from these statistics
  // (R h = r).
  double explained = 0.0, explained_velocity = 0.0;
  for (std::size_t i = 0; i < next->position.size(); ++i)
  {
    explained += next->position[i] * fit.r_position[i];
    explained_velocity += next->velocity[i] * fit.r_velocity[i];
  }
  next->error_variance = std::max(0.0, sea.displacement_variance - explained);
  next->wave_variance = sea.displacement_variance;
  next->velocity_error_variance = std::max(0.0, sea.velocity_variance - explained_velocity);
  next->mean = mean;
  previous_ = std::move(current_);
  current_ = std::move(next);
  stale_ = false;
  fade_ = previous_ ? 0.0 : 1.0;
}

}  // namespace periodic_bias_compensation
