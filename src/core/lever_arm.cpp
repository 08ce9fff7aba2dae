#include "periodic_bias_compensation/core/lever_arm.h"
#include "periodic_bias_compensation/core/turn_detector.h"

#include <algorithm>
#include <cmath>

namespace periodic_bias_compensation
{
LeverArm::LeverArm(const Eigen::Vector3d& offset) : offset_(offset)
{
}

void LeverArm::setOffset(const Eigen::Vector3d& offset)
{
  offset_ = offset;
  reset();
}

void LeverArm::reset()
{
  mean_.setZero();
  slow_.setZero();
  previous_.setZero();
  samples_ = 0.0;
}

LeverArmOutput LeverArm::update(const Eigen::Quaterniond& orientation, double dt)
{
  LeverArmOutput out;
  if (!active())
    return out;
  const Eigen::Matrix3d rotation = orientation.normalized().toRotationMatrix();
  const double heading = headingOf(rotation);
  const Eigen::AngleAxisd turn(heading, Eigen::Vector3d::UnitZ());
  // The tilt's displacement in the frame that turns with the heading.
  const Eigen::Vector3d tilted = turn.inverse() * (rotation * offset_);
  // Plain means over the first kTiltMemory, then moving ones (no start transient).
  samples_ += 1.0;
  const double memory = dt > 0.0 ? 1.0 - std::exp(-dt / kTiltMemory) : 0.0;
  const double weight = std::max(memory, 1.0 / samples_);
  mean_ += weight * (tilted - mean_);
  slow_ += weight * (mean_ - slow_);
  const Eigen::Vector3d wave = tilted - slow_;
  out.position = turn * wave;
  if (dt > 0.0 && samples_ > 1.0)
    out.velocity = turn * ((wave - previous_) / dt);
  previous_ = wave;
  return out;
}
}  // namespace periodic_bias_compensation
