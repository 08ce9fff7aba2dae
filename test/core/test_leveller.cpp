// Leveller: which level frame a sample gets, with and without the IMU's orientation.
#include <gtest/gtest.h>

#include "periodic_bias_compensation/core/leveller.h"

namespace periodic_bias_compensation
{
namespace
{
ImuSample atRest(const Quaternion& tilt, bool with_orientation)
{
  ImuSample s;
  s.specific_force = tilt.conjugate() * Vector3(0, 0, kStandardGravity);
  s.orientation = tilt;
  s.has_orientation = with_orientation;
  return s;
}
}  // namespace

// No orientation ever: the gravity direction levels the samples, the calibration window's mean
// replaces the first sample's.
TEST(Leveller, GravityWithoutOrientation)
{
  const Quaternion tilt(Eigen::AngleAxisd(0.1, Vector3::UnitX()));
  Leveller leveller;
  ImuSample s = atRest(tilt, false);
  leveller.orient(&s, 0.0, false, GyroAttitudeConfig());
  EXPECT_EQ(leveller.source(), LevelSource::kGravity);
  EXPECT_LT(leveller.levelAcceleration(s, kStandardGravity).norm(), 1e-9);
  EXPECT_TRUE(leveller.needsCalibration());
  const Quaternion other(Eigen::AngleAxisd(0.2, Vector3::UnitY()));
  leveller.calibrate(other.conjugate() * Vector3(0, 0, kStandardGravity), true);
  EXPECT_FALSE(leveller.needsCalibration());
  EXPECT_LT(leveller.levelAcceleration(atRest(other, false), kStandardGravity).norm(), 1e-9);
}

// Orientation that stops: the samples after it are levelled by the mean orientation from
// before (not by one instant's), and the calibration does not replace it.
TEST(Leveller, MeanOrientationAfterALoss)
{
  Leveller leveller;
  for (int k = 0; k < 100; ++k)
  {
    const double roll = 0.05 * (k % 2 == 0 ? 1.0 : -1.0) + 0.02;  // rolling about a 0.02 rad mean
    ImuSample s = atRest(Quaternion(Eigen::AngleAxisd(roll, Vector3::UnitX())), true);
    leveller.orient(&s, 0.01, false, GyroAttitudeConfig());
    leveller.levelAcceleration(s, kStandardGravity);
  }
  EXPECT_FALSE(leveller.needsCalibration());
  ImuSample lost = atRest(Quaternion(Eigen::AngleAxisd(0.02, Vector3::UnitX())), false);
  leveller.orient(&lost, 0.01, false, GyroAttitudeConfig());
  EXPECT_EQ(leveller.source(), LevelSource::kAttitudeBeforeLoss);
  leveller.calibrate(Vector3(0, 0, kStandardGravity), true);
  EXPECT_EQ(leveller.source(), LevelSource::kAttitudeBeforeLoss);
  EXPECT_LT(leveller.levelAcceleration(lost, kStandardGravity).norm(), 0.01);
}

// With the gyro attitude, samples without orientation get its attitude once it has started
// (kStartWindow at rest).
TEST(Leveller, GyroAttitudeOnceStarted)
{
  const Quaternion tilt(Eigen::AngleAxisd(0.1, Vector3::UnitY()));
  Leveller leveller;
  for (int k = 0; k <= static_cast<int>(kStartWindow * 100.0) + 1; ++k)
  {
    ImuSample s = atRest(tilt, false);
    leveller.orient(&s, k == 0 ? 0.0 : 0.01, true, GyroAttitudeConfig());
  }
  EXPECT_EQ(leveller.source(), LevelSource::kGyroAttitude);
  ImuSample s = atRest(tilt, false);
  leveller.orient(&s, 0.01, true, GyroAttitudeConfig());
  EXPECT_TRUE(s.has_orientation);
  EXPECT_LT(leveller.levelAcceleration(s, kStandardGravity).norm(), 1e-6);
  leveller.reset();
  EXPECT_EQ(leveller.source(), LevelSource::kNone);
}

}  // namespace periodic_bias_compensation
