// Basic types of the ship IMU simulator (no ROS).
//
// Frames: REP-103 world ENU (x east, y north, z up), body base_link (x forward, y left, z up).
// IMU convention REP-145: the accelerometer measures specific force INCLUDING gravity (a sensor
// at rest and level reads +g on z); orientation rotates sensor-frame vectors into ENU.
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "periodic_bias_compensation/core/types.h"

namespace periodic_bias_compensation::sim
{
using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Quaternion = Eigen::Quaterniond;

using periodic_bias_compensation::kStandardGravity;

/// Exact motion of the reference point base_link. Vectors in ENU unless stated otherwise.
struct Truth
{
  Vector3 position = Vector3::Zero();              ///< [m]
  Vector3 velocity = Vector3::Zero();              ///< [m/s]
  Vector3 acceleration = Vector3::Zero();          ///< [m/s^2], kinematic (no gravity)
  Quaternion attitude = Quaternion::Identity();    ///< base_link -> ENU
  Vector3 angular_rate = Vector3::Zero();          ///< body frame [rad/s]
  Vector3 angular_acceleration = Vector3::Zero();  ///< body frame [rad/s^2]
  Vector3 slow_position = Vector3::Zero();         ///< slow (route) part [m]
  Vector3 slow_velocity = Vector3::Zero();         ///< slow (route) part [m/s]
  Vector3 slow_acceleration = Vector3::Zero();     ///< slow (route) part [m/s^2]
  double slow_heading = 0.0;                       ///< heading of the slow motion, ENU yaw [rad]
  double slow_yaw_rate = 0.0;                      ///< rate of slow_heading [rad/s]
  Vector3 wave_position = Vector3::Zero();         ///< wave part, position = slow + wave [m]
  Vector3 wave_velocity = Vector3::Zero();         ///< wave part [m/s]
  Vector3 wave_acceleration = Vector3::Zero();     ///< wave part [m/s^2]
};

/// One simulated IMU sample with its truth.
struct Sample
{
  std::int64_t index = 0;                           ///< sample number, 0 for the first sample
  double elapsed = 0.0;                             ///< true time since the start of the scenario [s]
  double t = 0.0;                                   ///< true sample time, start_time + elapsed [s]
  double stamp = 0.0;                               ///< reported time stamp (t plus timestamp_jitter) [s]
  bool dropped = false;                             ///< the sensor lost this sample (dropouts); do not publish it
  Vector3 accel = Vector3::Zero();                  ///< specific force incl. gravity, sensor frame [m/s^2]
  Vector3 gyro = Vector3::Zero();                   ///< angular rate, sensor frame [rad/s]
  Quaternion orientation = Quaternion::Identity();  ///< reported sensor -> ENU
  double temperature = 0.0;                         ///< sensor temperature [degC], valid if has_temperature
  bool has_temperature = false;
  Truth truth;
};
}  // namespace periodic_bias_compensation::sim
