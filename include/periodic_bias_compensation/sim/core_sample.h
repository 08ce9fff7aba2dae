// The simulator's sample as the estimation core takes it. Header only, so that neither library
// links the other.
#pragma once

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation::sim
{
/// The reported stamp, specific force, angular rate and orientation (sensor -> ENU, REP-145).
inline ImuSample toImuSample(const Sample& s)
{
  ImuSample imu;
  imu.t = s.stamp;
  imu.specific_force = s.accel;
  imu.angular_rate = s.gyro;
  imu.has_orientation = true;
  imu.orientation = s.orientation;
  return imu;
}
}  // namespace periodic_bias_compensation::sim
