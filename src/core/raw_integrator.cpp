#include "periodic_bias_compensation/core/raw_integrator.h"

namespace periodic_bias_compensation
{
void RawIntegrator::add(double t, const Vector3& acceleration, bool restart)
{
  if (started_ && !restart && t > t_)
  {
    const double dt = t - t_;
    const Vector3 velocity_next = velocity_ + 0.5 * dt * (acceleration_ + acceleration);
    position_ += 0.5 * dt * (velocity_ + velocity_next);
    velocity_ = velocity_next;
  }
  started_ = true;
  t_ = t;
  acceleration_ = acceleration;
}

void RawIntegrator::reset()
{
  started_ = false;
  acceleration_.setZero();
  velocity_.setZero();
  position_.setZero();
}

}  // namespace periodic_bias_compensation
