#include "periodic_bias_compensation/core/gyro_attitude.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "periodic_bias_compensation/core/types.h"

namespace periodic_bias_compensation
{
namespace
{
/// Specific force whose magnitude departs from 1 g by more than this share is not taken as the
/// gravity direction (a slam, a crane lift) [-].
constexpr double kMaxForceDeparture = 0.3;
/// Shortest time constant of the tilt pull, used right after initialisation [s].
constexpr double kStartTimeConstant = 1.0;
/// Largest share of the tilt error corrected in one step (keeps the explicit step stable for
/// long sample intervals) [-].
constexpr double kMaxStepGain = 0.5;
/// Spread (standard deviation) of each gyro axis below which the start window is at rest [rad/s]
/// (a hull in waves rolls and pitches at 0.05 rad/s and more; a gyro's noise is 0.002).
constexpr double kStaticRateSpread = 0.02;
/// Spread of |specific force| below which the start window is at rest [m/s^2].
constexpr double kStaticForceSpread = 0.1;
}  // namespace

Eigen::Quaterniond levelFromSpecificForce(const Eigen::Vector3d& specific_force)
{
  // The rotation about u x z by acos(u . z) as (1 + u . z, u x z), normalised: a half-angle
  // quaternion, of unit norm to rounding even close to the opposite direction. Not Eigen's
  // FromTwoVectors, whose opposite-vector case instantiates a singular value decomposition that
  // takes longer to compile than the rest of the file.
  const Eigen::Vector3d u = specific_force.normalized();
  const double c = u.z();
  Eigen::Vector3d axis(u.y(), -u.x(), 0.0);
  if (c < -1.0 + 1e-12)
  {
    // Nearly opposite: half a turn about a horizontal axis normal to u.
    const double norm = axis.norm();
    axis = norm > 0.0 ? Eigen::Vector3d(axis / norm) : Eigen::Vector3d::UnitX();
    const double w2 = 0.5 * (1.0 + std::max(c, -1.0));
    const Eigen::Vector3d vec = axis * std::sqrt(1.0 - w2);
    return Eigen::Quaterniond(std::sqrt(w2), vec.x(), vec.y(), vec.z());
  }
  return Eigen::Quaterniond(1.0 + c, axis.x(), axis.y(), 0.0).normalized();
}

GyroAttitude::GyroAttitude(const GyroAttitudeConfig& config) : config_(config)
{
}

void GyroAttitude::reset()
{
  initialised_ = false;
  attitude_.setIdentity();
  bias_.setZero();
  elapsed_ = 0.0;
  start_ = StartWindow();
  block_sum_ = Block();
  block_count_ = block_elapsed_ = 0.0;
  blocks_filled_ = block_next_ = 0;
  quiet_ = false;
  rate_less_bias_.setZero();
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
  const bool gravity_like = std::abs(force - kStandardGravity) < kMaxForceDeparture * kStandardGravity;
  if (!initialised_)
  {
    start(angular_rate, specific_force, dt, gravity_like);
    return attitude_;
  }
  if (!(dt > 0.0))
    return attitude_;
  elapsed_ += dt;
  watchQuiet(angular_rate, specific_force, dt);
  rate_less_bias_ += std::min(1.0, dt / kQuietExitTime) * (angular_rate - bias_ - rate_less_bias_);
  if (quiet_ && rate_less_bias_.norm() > kQuietRateLimit)
  {
    quiet_ = false;
    blocks_filled_ = 0;
  }

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
  Eigen::Vector3d rate = k_p * error;
  if (quiet_)
  {
    if (config_.estimate_bias)
      bias_ += std::min(1.0, dt / kQuietBiasTime) * (angular_rate - bias_);
  }
  else
  {
    bias_ -= k_i * error * dt;
    rate += angular_rate - bias_;
  }
  const double angle = rate.norm() * dt;
  if (angle > 0.0)
    attitude_ = (attitude_ * Eigen::Quaterniond(Eigen::AngleAxisd(angle, rate.normalized()))).normalized();
  return attitude_;
}

void GyroAttitude::watchQuiet(const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& specific_force, double dt)
{
  block_sum_.rate += angular_rate;
  block_sum_.force += specific_force;
  ++block_count_;
  block_elapsed_ += dt;
  if (block_elapsed_ < 1.0)
    return;
  Block& newest = blocks_[block_next_];
  newest.rate = block_sum_.rate / block_count_;
  newest.force = block_sum_.force / block_count_;
  block_next_ = (block_next_ + 1) % kQuietBlocks;
  blocks_filled_ = std::min(blocks_filled_ + 1, kQuietBlocks);
  block_sum_ = Block();
  block_count_ = block_elapsed_ = 0.0;
  if (blocks_filled_ < kQuietBlocks)
  {
    quiet_ = false;
    return;
  }
  Eigen::Vector3d rate_min = newest.rate, rate_max = newest.rate, force_min = newest.force, force_max = newest.force;
  for (const Block& b : blocks_)
  {
    rate_min = rate_min.cwiseMin(b.rate);
    rate_max = rate_max.cwiseMax(b.rate);
    force_min = force_min.cwiseMin(b.force);
    force_max = force_max.cwiseMax(b.force);
  }
  quiet_ = (rate_max - rate_min).maxCoeff() < kQuietRateRange && (force_max - force_min).maxCoeff() < kQuietForceRange;
}

void GyroAttitude::start(const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& specific_force, double dt,
                         bool gravity_like)
{
  if (!gravity_like)
    return;
  // Welford's running means and spreads over the start window.
  StartWindow& w = start_;
  ++w.count;
  const Eigen::Vector3d rate_step = angular_rate - w.rate_mean;
  w.rate_mean += rate_step / w.count;
  w.rate_m2 += rate_step.cwiseProduct(angular_rate - w.rate_mean);
  w.force_mean += (specific_force - w.force_mean) / w.count;
  const double magnitude = specific_force.norm();
  const double magnitude_step = magnitude - w.magnitude_mean;
  w.magnitude_mean += magnitude_step / w.count;
  w.magnitude_m2 += magnitude_step * (magnitude - w.magnitude_mean);
  w.elapsed += dt > 0.0 ? dt : 0.0;
  if (w.elapsed < kStartWindow)
    return;
  const double n = std::max(1.0, w.count - 1.0);
  const bool at_rest =
      (w.rate_m2 / n).cwiseSqrt().maxCoeff() < kStaticRateSpread && std::sqrt(w.magnitude_m2 / n) < kStaticForceSpread;
  // Roll and pitch that turn the measured "up" onto z; yaw zero. At rest the window's mean
  // force is up and its mean rate the gyro bias (a consumer gyro's few degrees per second would
  // otherwise tilt the estimate by radians before the bias loop caught up); in motion, the newest
  // sample's force, and the bias is left to the loop.
  attitude_ = levelFromSpecificForce(at_rest ? w.force_mean : specific_force);
  if (at_rest && config_.estimate_bias)
    bias_ = w.rate_mean;
  started_at_rest_ = at_rest;
  initialised_ = true;
}

}  // namespace periodic_bias_compensation
