// The level frame of each sample (estimation core, no ROS).
//
// A sample with the IMU's orientation is levelled with it, and the orientation's mean over
// kAttitudeMemory is kept. A sample without one is levelled, in that order of preference, by
// the gyro attitude (GyroAttitude, when enabled: it starts from the IMU's last orientation if
// there was one), by that mean orientation from before the loss, or by the gravity direction
// (the newest sample's specific force until the calibration window's mean replaces it).
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/gyro_attitude.h"

namespace periodic_bias_compensation
{
class Leveller
{
public:
  /// Starts over (gyro attitude, mean orientation, level calibration); the last level frame and
  /// whether the last sample had an orientation are kept until the next sample.
  void reset();

  /// Gives a sample without orientation the gyro attitude's (use_gyro, once it has started) and
  /// updates the level frame for the samples that still have none.
  void orient(ImuSample* s, double dt, bool use_gyro, const GyroAttitudeConfig& gyro);

  /// The sample's specific force in the level frame less gravity [m/s^2].
  Vector3 levelAcceleration(const ImuSample& s, double gravity);

  /// The calibration window ended: with samples without orientation in it (and no mean
  /// orientation from before a loss), its mean specific force gives the level frame.
  void calibrate(const Vector3& mean_specific_force, bool any_without_orientation);

  /// The level frame is still to be calibrated for the last sample (it had no orientation).
  bool needsCalibration() const
  {
    return !calibrated_ && !last_had_orientation_;
  }
  const Quaternion& level() const
  {
    return level_;
  }
  LevelSource source() const
  {
    return gyro_levelled_ ? LevelSource::kGyroAttitude : source_;
  }
  const GyroAttitude& gyro() const
  {
    return gyro_;
  }

private:
  void updateLevel(const ImuSample& s, double dt);

  GyroAttitude gyro_;
  bool gyro_levelled_ = false;  ///< the last sample's orientation came from gyro_
  bool has_level_ = false;
  bool calibrated_ = false;
  LevelSource source_ = LevelSource::kNone;
  Quaternion attitude_ = Quaternion::Identity();  ///< mean IMU orientation
  long attitude_samples_ = 0;
  bool orientation_lost_ = false;  ///< the last sample had no orientation
  bool last_had_orientation_ = false;
  Quaternion level_ = Quaternion::Identity();
};

}  // namespace periodic_bias_compensation
