// The estimation core's vector and rotation types (no ROS).
#pragma once

#include <Eigen/Geometry>

namespace periodic_bias_compensation
{
using Vector3 = Eigen::Vector3d;
using Quaternion = Eigen::Quaterniond;

/// Standard gravity [m/s^2] (REP-103: ENU, z up; a sensor at rest reads +g on its up axis).
constexpr double kStandardGravity = 9.80665;
}  // namespace periodic_bias_compensation
