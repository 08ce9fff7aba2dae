// The simulator's sample as the estimation core takes it: the bridge the offline tools, the
// benchmarks and the tests that feed simulated data to the core use. Header only, and outside
// both libraries, so that neither includes or links the other.
#pragma once

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation
{
/// The reported stamp, specific force, angular rate and orientation (sensor -> ENU, REP-145).
inline ImuSample toImuSample(const sim::Sample& s)
{
  ImuSample imu;
  imu.t = s.stamp;
  imu.specific_force = s.accel;
  imu.angular_rate = s.gyro;
  imu.has_orientation = true;
  imu.orientation = s.orientation;
  return imu;
}
}  // namespace periodic_bias_compensation
