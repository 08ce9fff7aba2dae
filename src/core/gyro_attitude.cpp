#include "periodic_bias_compensation/core/gyro_attitude.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace periodic_bias_compensation
{
namespace
{
/// Specific force whose magnitude departs from 1 g by more than this share is not taken as the
/// gravity direction (a slam, a crane lift) [-].
constexpr double kMaxForceDeparture = 0.3;
constexpr double kGravity = 9.80665;
/// Shortest time constant of the tilt pull, used right after initialisation [s].
constexpr double kStartTimeConstant = 1.0;
/// Largest share of the tilt error corrected in one step (keeps the explicit step stable for
/// long sample intervals) [-].
constexpr double kMaxStepGain = 0.5;
}  // namespace

GyroAttitude::GyroAttitude(const GyroAttitudeConfig& config) : config_(config)
{
}

void GyroAttitude::reset()
{
  initialised_ = false;
  attitude_.setIdentity();
  bias_.setZero();
  elapsed_ = 0.0;
}

void GyroAttitude::reset(const Eigen::Quaterniond& start)
{
  reset();
  attitude_ = start.normalized();
  initialised_ = true;
  // A reported attitude needs no fast start (which would follow the wave accelerations).
  elapsed_ = std::numeric_limits<double>::infinity();
}

const Eigen::Quaterniond& GyroAttitude::update(const Eigen::Vector3d& angular_rate,
                                               const Eigen::Vector3d& specific_force, double dt)
{
  const double force = specific_force.norm();
  const bool gravity_like = std::abs(force - kGravity) < kMaxForceDeparture * kGravity;
  if (!initialised_)
  {
    if (gravity_like)
    {
      // Roll and pitch that turn the measured "up" onto z; yaw zero.
      attitude_ = Eigen::Quaterniond::FromTwoVectors(specific_force, Eigen::Vector3d::UnitZ());
      initialised_ = true;
    }
    return attitude_;
  }
  if (!(dt > 0.0))
    return attitude_;
  elapsed_ += dt;

  // The tilt pull starts fast (the first sample's force includes the wave acceleration) and
  // relaxes to tilt_time_constant; the bias integral runs only once it has.
  const double time_constant = std::min(std::max(elapsed_, kStartTimeConstant), config_.tilt_time_constant);
  const bool settled = elapsed_ >= config_.tilt_time_constant;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();
  if (gravity_like)
  {
    // Measured up cross estimated up (sensor frame): the rotation that brings the estimate
    // onto the measurement.
    const Eigen::Vector3d up_estimated = attitude_.conjugate() * Eigen::Vector3d::UnitZ();
    error = (specific_force / force).cross(up_estimated);
  }
  double k_p = 1.0 / time_constant;
  double k_i = 0.0;
  if (config_.estimate_bias && settled)
  {
    // Characteristic polynomial s^2 + k_p s + k_i with a double root at -1 / time_constant.
    k_p = 2.0 / time_constant;
    k_i = 1.0 / (time_constant * time_constant);
  }
  k_p = std::min(k_p, kMaxStepGain / dt);
  bias_ -= k_i * error * dt;

  const Eigen::Vector3d rate = angular_rate - bias_ + k_p * error;
  const double angle = rate.norm() * dt;
  if (angle > 0.0)
    attitude_ = (attitude_ * Eigen::Quaterniond(Eigen::AngleAxisd(angle, rate.normalized()))).normalized();
  return attitude_;
}

}  // namespace periodic_bias_compensation
