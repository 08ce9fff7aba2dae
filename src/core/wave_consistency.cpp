#include "periodic_bias_compensation/core/wave_consistency.h"

#include <algorithm>

namespace periodic_bias_compensation
{
void WaveConsistency::reset()
{
  measured_ = Band();
  output_ = Band();
  previous_velocity_ = 0.0;
  samples_ = 0.0;
  elapsed_ = 0.0;
  coefficients_dt_ = 0.0;
  weight_ = 1.0;
}

double WaveConsistency::Band::step(double value, const Coefficients& c)
{
  // The value less its slow mean (a first-order high-pass, its mean started as a plain mean, so
  // that no single sample, its noise, sets the start), then the low-passes.
  mean += c.slow * (value - mean);
  double x = value - mean;
  for (double& stage : low)
    x = stage += c.low_pass * (x - stage);
  power += c.averaging * (x * x - power);
  return power;
}

double WaveConsistency::update(double measured, double velocity, double noise_variance, double dt)
{
  if (!(dt > 0.0) || !std::isfinite(measured) || !std::isfinite(velocity) || !std::isfinite(noise_variance))
    return weight_;
  const double acceleration = (velocity - previous_velocity_) / dt;
  previous_velocity_ = velocity;
  samples_ += 1.0;
  if (samples_ < 2.0)  // the output's acceleration needs two samples
    return weight_;
  const double n = samples_ - 1.0;
  if (dt != coefficients_dt_)
  {
    // The step's filter coefficients, kept while the step is the same (a steady rate).
    coefficients_dt_ = dt;
    slow_ = 1.0 - std::exp(-2.0 * M_PI * min_frequency_ * dt);
    low_pass_ = 1.0 - std::exp(-2.0 * M_PI * kBandTop * dt);
    averaging_ = 1.0 - std::exp(-dt / kAveraging);
    // White noise through the low-passes: two one-poles of coefficient c = 1 - b pass
    // c^4 (1 + b^2) / (1 - b^2)^3 of its variance.
    const double b = 1.0 - low_pass_;
    noise_gain_ = std::pow(low_pass_, 4) * (1.0 + b * b) / std::pow(1.0 - b * b, 3);
  }
  Coefficients c;
  c.slow = std::max(slow_, 1.0 / n);
  c.low_pass = low_pass_;
  c.averaging = std::max(averaging_, 1.0 / n);
  const double measured_power = measured_.step(measured, c);
  const double output_power = output_.step(acceleration, c);
  const double noise_power = std::max(0.0, noise_variance) * noise_gain_;
  const double allowed = kExcess * (measured_power + noise_power);
  elapsed_ += dt;
  if (elapsed_ >= kSettle)
    weight_ = output_power > allowed ? std::sqrt(allowed / output_power) : 1.0;
  return weight_;
}

}  // namespace periodic_bias_compensation
