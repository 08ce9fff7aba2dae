#include "periodic_bias_compensation/core/broadband_wave.h"

#include <algorithm>

namespace periodic_bias_compensation
{
BroadbandWave::BroadbandWave(bool vertical, double corner_frequency, double min_frequency, bool companions)
  : vertical_(vertical),
    min_frequency_(min_frequency),
    companions_(companions),
    spectral_(kBandEdge * min_frequency, vertical, companions)
{
  configure(corner_frequency, min_frequency);
}

void BroadbandWave::configure(double corner_frequency, double min_frequency)
{
  min_frequency_ = min_frequency;
  fixed_.setCornerFrequency(corner_frequency);
  for (HeaveFilter& filter : residual_heave_)
    filter.setCornerFrequency(corner_frequency);
  spectral_.setMinFrequency(kBandEdge * min_frequency);
  reset();
}

void BroadbandWave::reset()
{
  fixed_.reset();
  spectral_.reset();
  for (HeaveFilter& filter : residual_heave_)
    filter.reset();
  residual_high_ = {};
  residual_leaky_ = {};
  residual_band_variance_ = {};
  difference_variance_ = 0.0;
  residual_samples_ = 0.0;
  samples_ = 0.0;
  elapsed_ = 0.0;
  weight_ = 0.0;
  returning_ = false;
  spectral_share_ = 0.0;
  low_ = {};
  low_variance_ = 0.0;
  wave_variance_ = 0.0;
  wave_velocity_variance_ = 0.0;
  previous_raw_ = NAN;
  noise_variance_ = 0.0;
  noise_floor_.reset();
  line_free_variance_ = 0.0;
  noise_blocks_ = 0.0;
}

BroadbandWaveOutput BroadbandWave::update(const BroadbandWaveInput& in)
{
  const double dt = in.dt;
  BroadbandWaveOutput out;
  const double omega_h = 2.0 * M_PI * min_frequency_;  // the wave band's edge [rad/s]
  out.estimate = fixed_.update(in.offset_free, dt);
  // Once the spectrum has been measured, the Wiener filter designed from it replaces the fixed
  // filter's displacement and velocity (its acceleration is the wave band's either way); a design
  // made stale by a turn hands back to the fixed filter, both with WienerHeave::kDesignFade.
  const double density = noiseDensitySquared(in.rate);
  if (in.turning && vertical_)
    spectral_.restartRecord();
  // A turn, or horizontal axes that may not be read for a manoeuvre: one in the horizontal records
  // (the vertical one begins anew at a turn, its companions with it).
  if (!vertical_ && (in.turning || (!in.allowed && in.manoeuvre)))
    spectral_.noteManoeuvre();
  const double period = in.rate_settled && in.rate > 0.0 ? 1.0 / in.rate : 0.0;
  const WienerHeaveOutput spectral = companions_ ? spectral_.update(in.offset_free, period, density, in.companions)
                                                 : spectral_.update(in.offset_free, period, density);
  if (dt > 0.0)
    spectral_share_ +=
        (1.0 - std::exp(-dt / WienerHeave::kDesignFade)) * ((spectral.valid ? 1.0 : 0.0) - spectral_share_);
  // The fade keeps the published output from stepping; where the blend publishes (next to) none of
  // the broadband estimate, a design replaces the fixed filter at once: the fixed filter's start
  // (up to a metre off in the first half minute on a sea) would otherwise ride into it.
  if (spectral.valid && weight_ < kMinWeight)
    spectral_share_ = 1.0;
  // The vertical axis measures what the harmonic model misses through four high-passes until the
  // first design (designed() stays true until reset()), every axis through two after it.
  const bool four_passes = vertical_ && !spectral_.designed();
  out.position_variance = fixed_.positionVariance(density);
  out.velocity_variance = fixed_.velocityVariance(density);
  if (spectral_share_ > 0.0)
  {
    const double share = spectral_share_;
    out.estimate.position += share * (spectral.position - out.estimate.position);
    out.estimate.velocity += share * (spectral.velocity - out.estimate.velocity);
    out.position_variance += share * (spectral.error_variance - out.position_variance);
    out.velocity_variance += share * (spectral.velocity_error_variance - out.velocity_variance);
  }
  if (dt > 0.0)
  {
    const double minute = 1.0 - std::exp(-dt / kAveraging);
    // Plain means over the first minute, then moving ones (an exponential mean started at zero
    // would read low for a minute).
    samples_ += 1.0;
    elapsed_ += dt;
    const double average = std::max(minute, 1.0 / samples_);
    // White noise of variance sigma^2 per sample: E[(a_k - a_k-1)^2] = 2 sigma^2 (a wave changes
    // little in one sample).
    if (std::isfinite(previous_raw_))
    {
      const double step = in.raw - previous_raw_;
      noise_variance_ += average * (0.5 * step * step - noise_variance_);
    }
    if (noise_floor_.add(in.raw))
    {
      // The same means over blocks: plain over the first kAveraging's, then moving.
      noise_blocks_ += 1.0;
      const double blocks = in.rate > 0.0 ? kAveraging * in.rate / NoiseFloor::kBlock : 1.0;
      const double block_average = std::max(1.0 / std::max(blocks, 1.0), 1.0 / noise_blocks_);
      line_free_variance_ += block_average * (noise_floor_.blockVariance() - line_free_variance_);
    }
    // Only against a locked model (before the first lock the residual is the whole wave).
    if (in.locked)
    {
      const double high = std::exp(-dt * omega_h);
      const bool started = residual_samples_ > 0.0;
      const auto high_pass = [high, started](HighPass* stage, double input) {
        stage->output = started ? high * (stage->output + input - stage->input) : 0.0;
        stage->input = input;
        return stage->output;
      };
      residual_samples_ += 1.0;
      const double average_missed = std::max(minute, 1.0 / residual_samples_);
      const auto accumulate = [&](std::size_t way, double missed) {
        residual_band_variance_[way] += average_missed * (missed * missed - residual_band_variance_[way]);
      };
      const auto measure_missed = [&](std::size_t way, double band) {
        accumulate(way, residual_heave_[way].update(band, residual_samples_ > 1.0 ? dt : 0.0).position);
      };
      const double two = high_pass(&residual_high_[1], high_pass(&residual_high_[0], in.residual));
      measure_missed(kTwoPasses, two);
      // Two high-passes and a double integration without drift removal: two leaky integrators,
      // 1 / (s + omega_h)^2 (the vertical axis only).
      if (vertical_)
      {
        const double leak = (1.0 - high) / omega_h;
        residual_leaky_[0] = high * residual_leaky_[0] + leak * in.residual;
        residual_leaky_[1] = high * residual_leaky_[1] + leak * residual_leaky_[0];
        accumulate(kTwoPassesLeaky, residual_leaky_[1]);
      }
      if (four_passes)
        measure_missed(kFourPasses, high_pass(&residual_high_[3], high_pass(&residual_high_[2], two)));
      const double difference = in.harmonic_position - out.estimate.position;
      difference_variance_ += average_missed * (difference * difference - difference_variance_);
    }
    const double low = 1.0 - std::exp(-dt * M_PI * min_frequency_);
    double below = out.estimate.position;
    for (double& stage : low_)
      below = stage += low * (below - stage);
    low_variance_ += average * (below * below - low_variance_);
    wave_variance_ += average * (out.estimate.position * out.estimate.position - wave_variance_);
    wave_velocity_variance_ += average * (out.estimate.velocity * out.estimate.velocity - wave_velocity_variance_);
  }
  previous_raw_ = in.raw;

  // Less the white noise through the high-passes and the filter (about 1 / s^2 there): n^2 times
  // the integral of omega^(2m - 4) df / (omega^2 + omega_h^2)^m over m high-passes,
  // 1 / (8 omega_h^3) for two, 1 / (64 omega_h^3) for four.
  const double noise = noiseDensitySquared(in.rate) / ((four_passes ? 64.0 : 8.0) * omega_h * omega_h * omega_h);
  // On the vertical axis, whose share may open from the first lock on, through two high-passes
  // the miss is measured both ways and the smaller counts: the fixed filter's drift removal rings
  // for a minute after the lock's first samples, the leaky integrators pass the slow content it
  // removes (a tilt leaking into one level frame; figures: docs/benchmarks.md, "Heave blend"). And
  // a mean square of the noise alone over T seconds scatters by 1 / sqrt(B T) of it, B the
  // noise-equivalent bandwidth of the chain (omega_h / 5 for two high-passes, 2 omega_h / 5 for
  // four; T at most twice kAveraging once the mean moves): a miss counts only beyond
  // kMissSignificance such scatters. On a narrow sea the broadband error is small, and any excess
  // would otherwise open the share. A horizontal axis measures no miss for kResidualSettling, past
  // both.
  double measured_missed = residual_band_variance_[four_passes ? kFourPasses : kTwoPasses];
  double significant = noise;
  if (vertical_)
  {
    if (!four_passes)
      measured_missed = std::min(measured_missed, residual_band_variance_[kTwoPassesLeaky]);
    const double averaged = in.rate > 0.0 ? std::min(residual_samples_ / in.rate, 2.0 * kAveraging) : 0.0;
    const double bandwidth = (four_passes ? 2.0 : 1.0) * omega_h / 5.0;
    if (averaged > 0.0)
      significant *= 1.0 + kMissSignificance / std::sqrt(bandwidth * averaged);
  }
  const double missed = std::max(0.0, measured_missed - significant);
  const double broadband = out.position_variance + std::max(low_variance_, low_.back() * low_.back());
  const bool miss_measured = vertical_ || elapsed_ >= kResidualSettling;
  double target = missed > 0.0 && miss_measured ? missed / (missed + broadband) : 0.0;
  // The residual sees only the wave band: bias wander below it never opens the share. But a model
  // locked elsewhere fits the acceleration and still turns it into the wrong displacement (it
  // divides by its own frequency squared), and the high-passes take part of a swell near the
  // band's edge. Once the residual opens the share, the displacements' difference sizes it:
  // E[(x_harmonic - x_broadband)^2] = V_missed + V_broadband for independent errors.
  if (target >= kMinWeight && difference_variance_ > broadband)
    target = std::max(target, 1.0 - broadband / difference_variance_);
  // A lock away from the displacement's peak describes the wrong part of the sea, and both
  // measures above read its miss low (figures: docs/benchmarks.md, "Heave blend"). The whole share
  // goes to the broadband estimate then, where there is a sea: the spectral design holds one (its
  // wave kSeaOverError times its expected error; at rest none above its error), or a measured miss
  // opened the share and the broadband output holds one (at rest its output is its own error; its
  // mean square since the start lags a design).
  const double peak = spectral_.peakFrequency();
  const bool holds_sea = spectral.valid && spectral.wave_variance > kSeaOverError * spectral.error_variance;
  const bool output_over_error = wave_variance_ > kSeaOverError * broadband;
  const bool output_holds_sea = target >= kMinWeight && output_over_error;
  if ((holds_sea || output_holds_sea) && spectral.valid && in.locked && in.frequency > 0.0 && peak > 0.0 &&
      std::abs(in.frequency - peak) > kOffPeak * peak)
    target = 1.0;
  // Without a lock the harmonic model's output is none: a design that holds a sea is then the
  // whole output, vertically from its first sample (the output's mean square since the start holds
  // the fixed filter's, and would close the share again for seconds), horizontally once that output
  // is kSeaOverError times the broadband error and not in the axis's first minute: a short record
  // of a hand's or a rig's motion reads as a sea there (the x-io recordings, docs/benchmarks.md),
  // and a broad sea holds a lock away from its displacement's peak, which opens the share above.
  // Nothing is published to fade from: the share comes in with kBlockedFade.
  const bool unlocked_sea = !in.locked && holds_sea && (vertical_ || (output_over_error && miss_measured));
  if (unlocked_sea)
    target = 1.0;
  // What the harmonic model's displacement misses: with a lock, what the residual or the difference
  // says; without one its output is none, so the whole wave. Velocity in proportion, at the
  // broadband estimate's own ratio of velocity to displacement.
  out.harmonic_miss_variance =
      in.locked ? std::max(missed, std::max(0.0, difference_variance_ - broadband)) : wave_variance_;
  out.harmonic_miss_velocity_variance =
      wave_variance_ > 0.0 ? out.harmonic_miss_variance * wave_velocity_variance_ / wave_variance_ : 0.0;
  const bool blocked = !vertical_ && !in.allowed;
  if (!vertical_ && (!spectral.valid || blocked))
    target = 0.0;
  if (target < kMinWeight)
    target = 0.0;
  // A hold moves the share out and back in quickly; the target's own moves are smoothed.
  if (blocked)
    returning_ = true;
  if (dt > 0.0)
    weight_ += (1.0 - std::exp(-dt / (returning_ || unlocked_sea ? kBlockedFade : kWeightTime))) * (target - weight_);
  if (!blocked && std::abs(target - weight_) < kReturned)
    returning_ = false;
  out.weight = weight_;
  return out;
}

}  // namespace periodic_bias_compensation
