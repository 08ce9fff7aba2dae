// The estimation core's vector and rotation types (no ROS).
#pragma once

#include <Eigen/Geometry>

namespace periodic_bias_compensation
{
using Vector3 = Eigen::Vector3d;
using Quaternion = Eigen::Quaterniond;
}  // namespace periodic_bias_compensation
