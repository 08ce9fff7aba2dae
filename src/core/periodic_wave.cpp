#include "periodic_bias_compensation/core/periodic_wave.h"

#include <algorithm>
#include <cmath>

namespace periodic_bias_compensation
{
void PeriodicWave::reset(int harmonics)
{
  model_.reset(harmonics);
  ready_ = false;
  previous_weight_ = 0.0;
  phase_ = 0.0;
  history_.clear();
}

void PeriodicWave::start(double frequency, double rate, double memory, int harmonics, bool fit_history,
                         double slow_span)
{
  retire();
  model_.reset(harmonics);
  phase_ = 0.0;
  frequency_ = frequency;
  start_velocity_ = 0.0;
  if (!fit_history || rate <= 0.0)
    return;
  const double step = 2.0 * M_PI * frequency / rate;
  const double lambda = std::exp(-1.0 / (rate * memory));
  const int period = static_cast<int>(std::ceil(rate / frequency));
  const int count = std::min(history_.size(), std::max(period, static_cast<int>(rate * memory)));
  // The newest kept sample (lag 1) is the previous one, at phase 0.
  model_.fit(count, -(count - 1) * step, step, lambda, [&](int k) { return history_.ago(count - k); });
  if (previous_weight_ > 0.0 || model_.updates() < rate / frequency)
    return;
  const double omega = 2.0 * M_PI * frequency;
  double a = 0.0, x = 0.0, v = 0.0, unused = 0.0, unused_too = 0.0;
  model_.evaluate(0.0, omega, &a, &x, &v, &unused, &unused_too);
  start_velocity_ = v;
  if (slow_span < 1.0 / frequency)
  {
    model_.evaluate(-omega * slow_span, omega, &a, &x, &v, &unused, &unused_too);
    start_velocity_ -= v;
  }
}

void PeriodicWave::retire()
{
  if (!ready_)
    return;
  previous_ = model_;
  previous_frequency_ = frequency_;
  previous_phase_ = phase_;
  previous_weight_ = 1.0;
  ready_ = false;
}

PeriodicWaveOutput PeriodicWave::update(double value, double frequency, double dt, double rate, double lambda)
{
  PeriodicWaveOutput out;
  frequency_ = frequency;
  const double omega = 2.0 * M_PI * frequency;
  phase_ = std::fmod(phase_ + omega * dt, 2.0 * M_PI);
  out.residual = model_.update(phase_, value, lambda);
  history_.push(value);
  // A fit of less than one period is not yet a description of the oscillation.
  if (model_.updates() >= rate / frequency)
  {
    model_.evaluate(phase_, omega, &out.acceleration, &out.position, &out.velocity, &out.position_variance_factor,
                    &out.velocity_variance_factor);
    ready_ = out.ready = true;
  }
  return out;
}

void PeriodicWave::fade(double dt, double* acceleration, double* position, double* velocity)
{
  if (previous_weight_ <= 0.0)
    return;
  const double omega = 2.0 * M_PI * previous_frequency_;
  previous_phase_ = std::fmod(previous_phase_ + omega * dt, 2.0 * M_PI);
  double a = 0.0, x = 0.0, v = 0.0, unused = 0.0, unused_too = 0.0;
  previous_.evaluate(previous_phase_, omega, &a, &x, &v, &unused, &unused_too);
  const double weight = previous_weight_;
  *acceleration = weight * a + (1.0 - weight) * *acceleration;
  *position = weight * x + (1.0 - weight) * *position;
  *velocity = weight * v + (1.0 - weight) * *velocity;
  previous_weight_ *= std::exp(-dt / kFadeTime);
  if (previous_weight_ < kFadeEnd)
    previous_weight_ = 0.0;
}
}  // namespace periodic_bias_compensation
