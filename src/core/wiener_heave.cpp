#include "periodic_bias_compensation/core/wiener_heave.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "background.h"
#include "periodic_bias_compensation/core/toeplitz.h"
#include "real_fft.h"

namespace periodic_bias_compensation
{
WienerHeave::WienerHeave(double min_frequency, bool vertical, bool companions)
  : min_frequency_(min_frequency), vertical_(vertical), channels_used_(companions ? kChannels : 1)
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

void WienerHeave::setMaxPhases(int max_phases)
{
  max_phases_ = std::max(1, max_phases);
  reset();
}

void WienerHeave::reset()
{
  dt_ = sized_dt_ = 0.0;
  decimation_ = 0;
  samples_ = 0;
  // The rings keep their memory (a reset at the calibration window's end would otherwise unmap
  // megabytes at a high rate and fault them in again over the next samples): what a reset
  // leaves in them is never read, as a FIR is never longer than the input held since.
  for (Channel& channel : channels_)
  {
    channel.first.clear();
    channel.second.clear();
    channel.first_sum = channel.second_sum = 0.0;
    channel.decimated.clear();
  }
  ring_length_ = 0;
  newest_ = 0;
  ring_of_phase_.clear();
  carried_ = Carried();
  since_design_ = 0.0;
  since_manoeuvre_ = since_gap_ = std::numeric_limits<double>::infinity();
  current_.reset();
  previous_.reset();
  fade_ = 1.0;
  peak_frequency_ = 0.0;
  stale_ = false;
  urgent_ = false;
  // A design still running keeps the transform it shares; the next one makes its own.
  if (pending_.valid())
    transform_.fft.reset();
  pending_ = {};
}

WienerHeave::WienerHeave(const WienerHeave& source, ForDesign)
  : min_frequency_(source.min_frequency_),
    vertical_(source.vertical_),
    channels_used_(source.channels_used_),
    dt_(source.dt_),
    decimation_(source.decimation_),
    samples_(source.samples_),
    ring_length_(source.ring_length_),
    since_manoeuvre_(source.since_manoeuvre_),
    since_gap_(source.since_gap_)
{
  for (int c = 0; c < channels_used_; ++c)
    channels_[c].decimated = source.channels_[c].decimated;
  transform_.fft = source.transform_.fft;
}

void WienerHeave::restartRecord()
{
  // The design made before the turn is taken up now, then marked stale with the others.
  if (pending_.valid())
    finishDesign();
  for (Channel& channel : channels_)
    channel.decimated.clear();
  since_design_ = 0.0;
  stale_ = current_ != nullptr;
}

WienerHeaveOutput WienerHeave::update(double a, double period, double noise_density_squared)
{
  return step(a, period, noise_density_squared, nullptr);
}

WienerHeaveOutput WienerHeave::update(double a, double period, double noise_density_squared,
                                      const Companions& companions)
{
  return step(a, period, noise_density_squared, &companions);
}

WienerHeaveOutput WienerHeave::step(double a, double period, double noise_density_squared, const Companions* companions)
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
    delay_samples_ = std::lround(kDesignDelay / dt_);
    // The longest FIR's taps (statistics(): lround(span * fs)), rounded as they are: a ceiling
    // makes 481 of a quotient a rounding error above 480 (at 2.8 kHz once the time base's period
    // is exact), and a reset would then size the rings anew.
    ring_length_ = std::max(1, static_cast<int>(std::lround(kMaxSpan / (decimation_ * dt_))));
    // Kept phases spread evenly over the period; all of them up to kMaxPhases.
    const int phases = std::min(decimation_, max_phases_);
    ring_of_phase_.assign(decimation_, -1);
    for (int ring = 0; ring < phases; ++ring)
      ring_of_phase_[static_cast<long>(ring) * decimation_ / phases] = ring;
    for (int c = 0; c < channels_used_; ++c)
    {
      channels_[c].first.assign(decimation_, 0.0);
      channels_[c].second.assign(decimation_, 0.0);
      const size_t history = static_cast<size_t>(ring_length_) * phases;
      if (channels_[c].history.size() != history)
        channels_[c].history = ZeroedBuffer(history);
    }
  }
  std::array<double, kChannels> input{ a, 0.0, 0.0 };
  if (channels_used_ > 1)
  {
    if (companions && std::isfinite((*companions)[0]) && std::isfinite((*companions)[1]))
      std::copy(companions->begin(), companions->end(), input.begin() + 1);
    else
    {
      // A gap: the companions' records hold zeros from here, which a design reading them would
      // take for the sea; this sample designs anew (from the own input alone), and takes the
      // design up at once (a pending one first, which may read them).
      since_gap_ = 0.0;
      if (pending_.valid())
        finishDesign();
      if (readsCompanions())
      {
        since_design_ = std::numeric_limits<double>::infinity();
        urgent_ = true;
      }
    }
  }
  // Two moving averages (running sums over circular buffers of decimation_ values).
  const int slot = static_cast<int>(samples_ % decimation_);
  // Sample m goes to the ring of its phase m mod D (if kept), place (m / D) mod ring_length_.
  const int ring = ring_of_phase_[slot];
  if (ring >= 0)
    newest_ = static_cast<int>(ring * ring_length_ + (samples_ / decimation_) % ring_length_);
  std::array<double, kChannels> low{};
  for (int c = 0; c < channels_used_; ++c)
  {
    Channel& channel = channels_[c];
    channel.first_sum += input[c] - channel.first[slot];
    channel.first[slot] = input[c];
    const double once = channel.first_sum / decimation_;
    channel.second_sum += once - channel.second[slot];
    channel.second[slot] = once;
    low[c] = channel.second_sum / decimation_;
    if (ring >= 0)
      channel.history[newest_] = low[c];
  }
  ++samples_;
  if (samples_ < 2 * decimation_)
    return out;  // the averages are not full yet
  if (samples_ % decimation_ == 0)
  {
    const size_t most = static_cast<size_t>(kDesignWindow / (decimation_ * dt_));
    for (int c = 0; c < channels_used_; ++c)
    {
      std::vector<double>& decimated = channels_[c].decimated;
      decimated.push_back(low[c]);
      if (decimated.size() > most)
        decimated.erase(decimated.begin(), decimated.begin() + (decimated.size() - most));
    }
  }
  since_design_ += dt_;
  since_manoeuvre_ += dt_;
  since_gap_ += dt_;
  const double recorded = record().size() * decimation_ * dt_;
  const double interval = recorded < kEarlyRecord ? kEarlyRedesignInterval : kRedesignInterval;
  const double first = current_ ? kRestartDesign : kFirstDesign;
  if (!pending_.valid() && (current_ && !stale_ ? since_design_ >= interval : recorded >= first) &&
      static_cast<int>(record().size()) >= kMinSegment)
  {
    startDesign(noise_density_squared, urgent_ ? 0 : delay_samples_);
    since_design_ = 0.0;
    urgent_ = false;
  }
  if (pending_.valid() && samples_ >= pending_due_)
    finishDesign();
  if (!current_)
    return out;
  const bool fading = previous_ != nullptr;
  if (fading)
    fade_ = std::min(1.0, fade_ + dt_ / kDesignFade);
  if (ring >= 0)
  {
    apply(*current_, &out.position, &out.velocity);
    if (fading)
    {
      double x_old = 0.0, v_old = 0.0;
      apply(*previous_, &x_old, &v_old);
      out.position = fade_ * out.position + (1.0 - fade_) * x_old;
      out.velocity = fade_ * out.velocity + (1.0 - fade_) * v_old;
    }
    // The slopes of both outputs since the last kept phase: displacement and velocity are each
    // their own estimate (the velocity is not the displacement's derivative), so each is carried
    // along its own.
    if (carried_.made > 0)
    {
      const double span = (samples_ - carried_.sample) * dt_;
      carried_.position_slope = (out.position - carried_.position) / span;
      carried_.velocity_slope = (out.velocity - carried_.velocity) / span;
    }
    ++carried_.made;
    carried_.sample = samples_;
    carried_.position = out.position;
    carried_.velocity = out.velocity;
  }
  else if (carried_.made >= 2)
  {
    const double since = (samples_ - carried_.sample) * dt_;
    out.position = carried_.position + since * carried_.position_slope;
    out.velocity = carried_.velocity + since * carried_.velocity_slope;
  }
  if (fading && fade_ >= 1.0)
    previous_.reset();
  if (ring < 0 && carried_.made < 2)
    return out;  // a sample between kept phases has an output once two kept phases have one
  out.error_variance = current_->error_variance;
  out.velocity_error_variance = current_->velocity_error_variance;
  out.wave_variance = current_->wave_variance;
  out.valid = !stale_;
  return out;
}

void WienerHeave::Design::prepare()
{
  for (int c = 0; c < kChannels; ++c)
  {
    std::reverse(position[c].begin(), position[c].end());
    std::reverse(velocity[c].begin(), velocity[c].end());
    double position_sum = 0.0, velocity_sum = 0.0;
    for (std::size_t k = 0; k < position[c].size(); ++k)
    {
      position_sum += position[c][k];
      velocity_sum += velocity[c][k];
    }
    position_offset[c] = mean[c] * position_sum;
    velocity_offset[c] = mean[c] * velocity_sum;
  }
}

void WienerHeave::apply(const Design& d, double* x, double* v) const
{
  using Values = Eigen::Map<const Eigen::VectorXd>;
  // The values D samples apart ending at the newest lie next to each other in its ring, newest
  // last: the newer ones up to the newest, the older ones (if the taps reach past the ring's
  // start) at the ring's end. Dot products with the taps oldest first, vectorised.
  const int place = newest_ % ring_length_;
  *x = *v = 0.0;
  for (int c = 0; c < kChannels && !d.position[c].empty(); ++c)
  {
    const double* ring = channels_[c].history.data() + (newest_ / ring_length_) * ring_length_;
    const int taps = static_cast<int>(d.position[c].size());
    const int newer = std::min(taps, place + 1);
    const int older = taps - newer;
    const Values position(d.position[c].data(), taps);
    const Values velocity(d.velocity[c].data(), taps);
    const Values recent(ring + place + 1 - newer, newer);
    const Values wrapped(ring + ring_length_ - older, older);
    *x += position.tail(newer).dot(recent) + position.head(older).dot(wrapped) - d.position_offset[c];
    *v += velocity.tail(newer).dot(recent) + velocity.head(older).dot(wrapped) - d.velocity_offset[c];
  }
}

std::vector<double> WienerHeave::welch(int segment, double mean, std::vector<double>* response) const
{
  RealFft& fft = *transform_.fft;
  const std::vector<double>& decimated = record();
  const int n = static_cast<int>(decimated.size());
  const double fs = 1.0 / (decimation_ * dt_);
  const int bins = kDftSize / 2 + 1;
  std::vector<double> density(bins, 0.0);
  double window_power = 0.0;
  const std::vector<double> window = hannWindow(segment, &window_power);
  int segments = 0;
  for (int start = n - segment; start >= 0; start -= std::max(1, segment / 2), ++segments)
  {
    for (int i = 0; i < segment; ++i)
      fft.in[i] = window[i] * (decimated[start + i] - mean);
    std::fill(fft.in + segment, fft.in + kDftSize, 0.0);
    fft.execute();
    for (int k = 0; k < bins; ++k)
      density[k] += fft.power(k);
  }
  for (double& d : density)
    d /= segments * window_power * fs;
  *response = windowResponse(segment);
  return density;
}

std::vector<double> WienerHeave::windowResponse(int segment) const
{
  // The window spreads every line over neighbouring bins (over +-2 bins of a segment in its main
  // lobe). Its response, relative to its peak:
  RealFft& fft = *transform_.fft;
  double window_power = 0.0;
  const std::vector<double> window = hannWindow(segment, &window_power);
  for (int i = 0; i < kDftSize; ++i)
    fft.in[i] = i < segment ? window[i] : 0.0;
  fft.execute();
  std::vector<double> response(kDftSize / 2 + 1);
  for (std::size_t k = 0; k < response.size(); ++k)
    response[k] = fft.power(static_cast<int>(k)) / fft.power(0);
  return response;
}

std::vector<double> WienerHeave::burg(int order, double mean) const
{
  // Forward and backward prediction errors; each stage's reflection coefficient minimises their
  // summed power (Burg), which keeps the model stable (|k| < 1). Stage m pairs forward[i] with
  // backward[i - 1], i = m..n-1; the backward errors are kept shifted by m (backward[i] at
  // backward_shifted[i - m]), so that both runs start at fixed places and every pass is a
  // vectorised one over contiguous values.
  const std::vector<double>& decimated = record();
  const int n = static_cast<int>(decimated.size());
  Eigen::VectorXd forward(n), backward_shifted(n), old_forward(n);
  std::vector<double> a(1, 1.0), previous;
  for (int i = 0; i < n; ++i)
    forward[i] = decimated[i] - mean;
  backward_shifted = forward;
  double power = forward.squaredNorm() / n;
  for (int m = 1; m <= order && m < n; ++m)
  {
    const int length = n - m;
    auto f = forward.segment(m, length);
    auto b = backward_shifted.head(length);
    const double cross = f.dot(b);
    const double sum = f.squaredNorm() + b.squaredNorm();
    if (!(sum > 0.0))
      break;
    const double k = -2.0 * cross / sum;
    old_forward.head(length) = f;
    f += k * b;
    b += k * old_forward.head(length);
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
  const double length = static_cast<double>(record().size()) / fs;
  const int first = kind == Estimate::kShortBurg
                        ? std::min(bins, static_cast<int>(std::ceil((min_frequency_ + kEdgeResolution / length) / df)))
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

std::complex<double> WienerHeave::lowPass(double gain, double omega) const
{
  return gain * std::polar(1.0, -omega * (decimation_ - 1) * dt_);
}

template <typename Spectrum>
std::vector<double> WienerHeave::correlation(const Spectrum& spectrum, int taps) const
{
  RealFft& fft = *transform_.fft;
  for (int k = 0; k < kDftSize / 2 + 1; ++k)
  {
    const std::complex<double> value = spectrum(k);
    fft.out[k][0] = value.real();
    fft.out[k][1] = value.imag();
  }
  fft.inverse();
  return std::vector<double>(fft.in, fft.in + taps);
}

WienerHeave::Statistics WienerHeave::statistics(const Wave& w) const
{
  Statistics out;
  if (!(w.peak_frequency > 0.0))
    return out;  // no wave in the spectrum
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
  std::vector<std::complex<double>>& cross = out.cross;
  cross.assign(bins, 0.0);
  for (int k = 1; k < bins; ++k)
  {
    const double f = k * df, omega = 2.0 * M_PI * f;
    cross[k] = -std::conj(lowPass(w.gain[k], omega)) * w.wave[k] / (omega * omega);
  }
  // Correlations at lags 0..taps-1, the velocity's cross-spectrum j omega times the
  // displacement's.
  out.autocorrelation = correlation([&](int k) { return std::complex<double>(w.density[k] * df); }, taps);
  out.r_position = correlation([&](int k) { return cross[k] * df; }, taps);
  out.r_velocity =
      correlation([&](int k) { return std::complex<double>(0.0, 2.0 * M_PI * k * df) * cross[k] * df; }, taps);
  return out;
}

void WienerHeave::startDesign(double noise_density_squared, long delay)
{
  if (!transform_.fft)
    transform_.fft = std::make_shared<RealFft>(kDftSize);
  std::shared_ptr<const WienerHeave> copy(new WienerHeave(*this, ForDesign{}));
  pending_ = designTask([copy, noise_density_squared] { return copy->design(noise_density_squared); },
                        background_ && delay > 0);
  pending_due_ = samples_ + delay;
}

void WienerHeave::finishDesign()
{
  // Not made yet: the designs queued meanwhile (other axes', other instances') are made here
  // while the design thread makes this one.
  const Outcome outcome = awaitDesign(pending_);
  pending_ = {};
  if (!outcome.design)
    return;
  peak_frequency_ = outcome.peak_frequency;
  previous_ = std::move(current_);
  current_ = outcome.design;
  stale_ = false;
  fade_ = previous_ ? 0.0 : 1.0;
}

WienerHeave::Outcome WienerHeave::design(double noise_density_squared) const
{
  const int n = static_cast<int>(record().size());
  std::array<double, kChannels> means{};
  for (int c = 0; c < channels_used_; ++c)
  {
    for (double value : channels_[c].decimated)
      means[c] += value;
    means[c] /= n;
  }
  const double mean = means[0];

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
  const double length = n * decimation_ * dt_;
  if ((vertical_ || since_manoeuvre_ > length) && n >= 2 * kSegment)
    sea = wave(burg(kMaxOrder, mean), {}, noise_density_squared, Estimate::kBurg);
  else
  {
    std::vector<double> response;
    std::vector<double> density = welch(n < 2 * kSegment ? n : kSegment, mean, &response);
    sea = wave(std::move(density), response, noise_density_squared, Estimate::kWelch);
    if (vertical_ && sea.peak_frequency * length < kResolvedCycles)
      sea = wave(burg(std::min(kMaxOrder, static_cast<int>(kShortOrder * n)), mean), {}, noise_density_squared,
                 Estimate::kShortBurg);
  }
  const Statistics fit = statistics(sea);
  if (fit.autocorrelation.empty())
  {
    // No wave in the spectrum: no heave.
    auto none = std::make_shared<Design>();
    none->position[0].assign(1, 0.0);
    none->velocity[0].assign(1, 0.0);
    none->mean = means;
    none->prepare();
    return { std::move(none), 0.0 };
  }
  auto next = std::make_shared<Design>();
  std::vector<std::vector<double>> taps;
  if (!solveToeplitz(fit.autocorrelation, { fit.r_position, fit.r_velocity }, &taps))
    return {};  // keep the last design, and its peak
  next->position[0] = std::move(taps[0]);
  next->velocity[0] = std::move(taps[1]);
  // The expected error E[(x - h a)^2] = var(x) - h r of taps solved from these statistics
  // (R h = r).
  double explained = 0.0, explained_velocity = 0.0;
  for (std::size_t i = 0; i < next->position[0].size(); ++i)
  {
    explained += next->position[0][i] * fit.r_position[i];
    explained_velocity += next->velocity[0][i] * fit.r_velocity[i];
  }
  next->error_variance = std::max(0.0, sea.displacement_variance - explained);
  next->wave_variance = sea.displacement_variance;
  next->velocity_error_variance = std::max(0.0, sea.velocity_variance - explained_velocity);
  next->mean = means;
  // With companions and no manoeuvre in the record, a design that reads all three inputs where it
  // expects less error: on a horizontal axis Welch's from kHorizontalCrossSegments Welch segments
  // where its own design holds a sea, and where that one is not taken, as on the vertical axis, the
  // one from the own estimate once the record holds kCrossSegments.
  const double segments = std::floor(static_cast<double>(n - kSegment) / (kSegment / 2)) + 1.0;
  const bool companions = channels_used_ > 1 && std::min(since_manoeuvre_, since_gap_) >= length;
  Design joint;
  if (companions && !vertical_ && segments >= kHorizontalCrossSegments &&
      next->wave_variance > kCompanionSea * next->error_variance &&
      welchCompanionDesign(means, noise_density_squared, &joint) && joint.error_variance < next->error_variance)
    *next = std::move(joint);
  else if (companions && segments >= kCrossSegments && companionDesign(sea, fit, means, &joint) &&
           joint.error_variance < next->error_variance)
    *next = std::move(joint);
  next->prepare();
  return { std::move(next), sea.peak_frequency };
}

WienerHeave::SpectralMatrix WienerHeave::welchMatrix(const std::array<double, kChannels>& mean, int* segments) const
{
  using Complex = std::complex<double>;
  RealFft& fft = *transform_.fft;
  const int n = static_cast<int>(record().size());
  const double fs = 1.0 / (decimation_ * dt_);
  const int bins = kDftSize / 2 + 1;
  double window_power = 0.0;
  const std::vector<double> window = hannWindow(kSegment, &window_power);
  SpectralMatrix matrix;
  for (int a = 0; a < kChannels; ++a)
    for (int b = 0; b < kChannels; ++b)
      matrix[a][b].assign(bins, 0.0);
  std::array<std::vector<Complex>, kChannels> transform;
  *segments = 0;
  for (int start = n - kSegment; start >= 0; start -= kSegment / 2, ++*segments)
  {
    for (int c = 0; c < kChannels; ++c)
    {
      for (int i = 0; i < kSegment; ++i)
        fft.in[i] = window[i] * (channels_[c].decimated[start + i] - mean[c]);
      std::fill(fft.in + kSegment, fft.in + kDftSize, 0.0);
      fft.execute();
      transform[c].resize(bins);
      for (int k = 0; k < bins; ++k)
        transform[c][k] = Complex(fft.out[k][0], fft.out[k][1]);
    }
    for (int a = 0; a < kChannels; ++a)
      for (int b = a; b < kChannels; ++b)
        for (int k = 0; k < bins; ++k)
          matrix[a][b][k] += transform[a][k] * std::conj(transform[b][k]);
  }
  const double normalisation = 1.0 / (*segments * window_power * fs);
  for (int a = 0; a < kChannels; ++a)
    for (int b = a; b < kChannels; ++b)
      for (int k = 0; k < bins; ++k)
      {
        matrix[a][b][k] *= normalisation;
        matrix[b][a][k] = std::conj(matrix[a][b][k]);
      }
  return matrix;
}

bool WienerHeave::solveJoint(const SpectralMatrix& matrix, const std::vector<double>& own_autocorrelation,
                             const Wave& sea, const Statistics& own, int taps, double loading, bool bounded,
                             const std::array<double, kChannels>& mean, Design* next) const
{
  using Complex = std::complex<double>;
  const double fs = 1.0 / (decimation_ * dt_);
  const double df = fs / kDftSize;
  // The normal equations sum_j E[u(n - i) u(n - j)^T] h_j = E[x(n) u(n - i)]: block (i, j) is
  // R(j - i), R(lag)(a, b) = E[u_a(n) u_b(n - lag)], so block r[lag] = R(lag)^T; the right-hand
  // sides E[x(n) u_c(n - lag)], the displacement's cross-spectrum with companion c
  // -S_0c / (omega^2 AA) where the own axis holds a wave (that of the own input from its
  // statistics).
  std::vector<Eigen::Matrix3d> blocks(taps);
  for (int a = 0; a < kChannels; ++a)
    for (int b = 0; b < kChannels; ++b)
    {
      const std::vector<double> r = a == 0 && b == 0 && !own_autocorrelation.empty()
                                        ? own_autocorrelation
                                        : correlation([&](int k) { return matrix[a][b][k] * df; }, taps);
      for (int lag = 0; lag < taps; ++lag)
        blocks[lag](b, a) = r[lag];
    }
  const double white = loading * blocks[0].trace() / kChannels;
  for (int c = 0; c < kChannels; ++c)
    blocks[0](c, c) += white;
  // The companions' cross-spectra with the own input say at most the own wave: where they would
  // explain more of it (p C^-1 p^H, p the row of cross-spectra, C the companions' matrix) than the
  // wave holds, the noise floor taken off, they are scaled to it.
  const int bins = kDftSize / 2 + 1;
  std::vector<double> bound(bins, 1.0);
  if (bounded)
    for (int k = 1; k < bins; ++k)
    {
      const Complex p1 = matrix[0][1][k], p2 = matrix[0][2][k];
      const Complex c11 = matrix[1][1][k], c12 = matrix[1][2][k], c21 = matrix[2][1][k], c22 = matrix[2][2][k];
      const Complex determinant = c11 * c22 - c12 * c21;
      if (!(std::abs(determinant) > 0.0))
        continue;
      // p C^-1 p^H with C^-1 = [c22 -c12; -c21 c11] / det.
      const double explained =
          ((p1 * (c22 * std::conj(p1) - c12 * std::conj(p2)) + p2 * (c11 * std::conj(p2) - c21 * std::conj(p1))) /
           determinant)
              .real();
      const double held = sea.wave[k] * sea.gain[k] * sea.gain[k];
      if (explained > held)
        bound[k] = std::sqrt(held / explained);
    }
  Eigen::MatrixXd rhs(3 * taps, 2);
  for (int c = 0; c < kChannels; ++c)
  {
    const auto displacement_cross = [&](int k) {
      if (c == 0)
        return own.cross[k];
      if (k == 0 || !(sea.wave[k] > 0.0))
        return Complex(0.0);
      const double omega = 2.0 * M_PI * k * df;
      return -bound[k] * matrix[0][c][k] / (omega * omega * lowPass(sea.gain[k], omega));
    };
    const std::vector<double> position = correlation([&](int k) { return displacement_cross(k) * df; }, taps);
    const std::vector<double> velocity =
        correlation([&](int k) { return Complex(0.0, 2.0 * M_PI * k * df) * displacement_cross(k) * df; }, taps);
    for (int lag = 0; lag < taps; ++lag)
    {
      rhs(3 * lag + c, 0) = position[lag];
      rhs(3 * lag + c, 1) = velocity[lag];
    }
  }
  Eigen::MatrixXd solution;
  if (!solveBlockToeplitz(blocks, rhs, &solution))
    return false;
  // The expected errors, var(x) - h r as for one input (with white noise added to the inputs,
  // h^T W h above the error of these taps in the spectrum designed from).
  const Eigen::Vector2d explained = (solution.cwiseProduct(rhs)).colwise().sum();
  next->error_variance = std::max(0.0, sea.displacement_variance - explained[0]);
  next->velocity_error_variance = std::max(0.0, sea.velocity_variance - explained[1]);
  next->wave_variance = sea.displacement_variance;
  next->mean = mean;
  for (int c = 0; c < kChannels; ++c)
  {
    next->position[c].resize(taps);
    next->velocity[c].resize(taps);
    for (int lag = 0; lag < taps; ++lag)
    {
      next->position[c][lag] = solution(3 * lag + c, 0);
      next->velocity[c][lag] = solution(3 * lag + c, 1);
    }
  }
  return true;
}

bool WienerHeave::companionDesign(const Wave& sea, const Statistics& own, const std::array<double, kChannels>& mean,
                                  Design* next) const
{
  const int bins = kDftSize / 2 + 1;
  int segments = 0;
  SpectralMatrix matrix = welchMatrix(mean, &segments);
  // The matrix designed from: the own estimate on the diagonal (its autocorrelation, passed on;
  // Welch's for the companions), each cross-spectrum shrunk by how far its coherence stands above
  // chance, 2 / K for K segments, the own input's scaled to the own estimate (its coherence kept).
  const double chance = 2.0 / segments;
  for (int k = 0; k < bins; ++k)
  {
    std::array<double, kChannels> auto_density{};
    for (int c = 0; c < kChannels; ++c)
      auto_density[c] = matrix[c][c][k].real();
    const double own_scale = auto_density[0] > 0.0 ? std::sqrt(sea.density[k] / auto_density[0]) : 0.0;
    for (int a = 0; a < kChannels; ++a)
      for (int b = a + 1; b < kChannels; ++b)
      {
        const double product = auto_density[a] * auto_density[b];
        const double coherence = product > 0.0 ? std::norm(matrix[a][b][k]) / product : 0.0;
        const double weight = std::clamp((coherence - chance) / (1.0 - chance), 0.0, 1.0);
        matrix[a][b][k] *= weight * (a == 0 ? own_scale : 1.0);
        matrix[b][a][k] = std::conj(matrix[a][b][k]);
      }
  }
  const double fs = 1.0 / (decimation_ * dt_);
  const int taps =
      std::min(static_cast<int>(own.autocorrelation.size()), static_cast<int>(std::lround(kCrossSpan * fs)));
  return solveJoint(matrix, own.autocorrelation, sea, own, taps, 0.0, false, mean, next);
}

bool WienerHeave::welchCompanionDesign(const std::array<double, kChannels>& mean, double noise_density_squared,
                                       Design* next) const
{
  int segments = 0;
  const SpectralMatrix matrix = welchMatrix(mean, &segments);
  // The own input's wave in the matrix's own density (the noise floor and what the band owes the
  // lines below it taken off): one estimate throughout, no mix of resolutions.
  std::vector<double> density(matrix[0][0].size());
  for (std::size_t k = 0; k < density.size(); ++k)
    density[k] = matrix[0][0][k].real();
  const std::vector<double> response = windowResponse(kSegment);
  const Wave sea = wave(std::move(density), response, noise_density_squared, Estimate::kWelch);
  const Statistics own = statistics(sea);
  if (own.autocorrelation.empty())
    return false;
  const double fs = 1.0 / (decimation_ * dt_);
  const int taps =
      std::min(static_cast<int>(own.autocorrelation.size()), static_cast<int>(std::lround(kCrossSpan * fs)));
  return solveJoint(matrix, {}, sea, own, taps, kLoading, true, mean, next);
}

}  // namespace periodic_bias_compensation
