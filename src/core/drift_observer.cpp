#include "periodic_bias_compensation/core/drift_observer.h"

#include <algorithm>
#include <cmath>

namespace periodic_bias_compensation
{
void DriftObserver::update(double acceleration, double dt, double time_constant, bool use_bias, bool learn_bias)
{
  const double w = 1.0 / time_constant;
  const double k1 = 4.0 * w, k2 = 6.0 * w * w;
  const double k3 = use_bias ? 4.0 * w * w * w : 0.0;
  const double k4 = use_bias ? w * w * w * w : 0.0;
  const double bias = use_bias ? bias_ : 0.0;
  k1_ = k1;
  const double split = std::ceil(w * dt / 0.1);
  if (split > kMaxSteps)
  {
    p_ = v_ = 0.0;
  }
  else
  {
    const int steps = std::max(1, static_cast<int>(split));
    const double h = dt / steps;
    for (int k = 0; k < steps; ++k)
    {
      v_ += (acceleration - (use_bias ? bias_ : 0.0) - k2 * p_) * h;
      p_ += (v_ - k1 * p_) * h;
      if (learn_bias)
      {
        bias_ += (k3 * p_ + bias_rate_) * h;
        bias_rate_ += k4 * p_ * h;
      }
    }
  }
  d_v_ = -(bias + k2 * p_) * dt;
  d_p_ = -k1 * p_ * dt;
}

void DriftObserver::noiseVariances(double acceleration_variance, double rate, double time_constant, double* position,
                                   double* velocity)
{
  const double w = 1.0 / time_constant;
  const double density = 2.0 * acceleration_variance * (rate > 0.0 ? 1.0 / rate : 0.0);
  *position = density / (64.0 * w * w * w);
  *velocity = 5.0 * density / (64.0 * w);
}
}  // namespace periodic_bias_compensation
