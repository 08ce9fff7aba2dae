// Constant-bias calibration file (YAML), read and written by the core, no ROS.
#pragma once

#include <string>

#include <Eigen/Core>

namespace periodic_bias_compensation
{
/// Reads `constant_bias: [bx, by, bz]` [m/s^2, level ENU frame] from a YAML file.
/// Returns false with a message naming the file and key on any error.
bool loadCalibration(const std::string& path, Eigen::Vector3d* bias, std::string* why);
/// Writes the same format (with a comment saying what and when). False with a message on error.
bool saveCalibration(const std::string& path, const Eigen::Vector3d& bias, std::string* why);
}  // namespace periodic_bias_compensation
