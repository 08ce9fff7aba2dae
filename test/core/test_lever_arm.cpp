// LeverArm: the wave part of an IMU's offset turned by the hull's tilt; a trim, a standing heel
// and a turn are not wave.
#include <gtest/gtest.h>

#include <cmath>

#include "periodic_bias_compensation/core/lever_arm.h"

namespace periodic_bias_compensation
{
namespace
{
Eigen::Quaterniond attitude(double roll, double pitch, double yaw)
{
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
}
}  // namespace

TEST(LeverArm, NoOffsetNothing)
{
  LeverArm lever;
  EXPECT_FALSE(lever.active());
  const LeverArmOutput out = lever.update(attitude(0.1, 0.05, 1.0), 0.01);
  EXPECT_EQ(out.position.norm(), 0.0);
  EXPECT_EQ(out.velocity.norm(), 0.0);
}

// Pitching about a trim, heading 30 degrees: the IMU 5 m aft and 4 m up moves by R r; its
// oscillating part is what is returned, within the slow means' error at 0.08 Hz.
TEST(LeverArm, PitchAboutATrimIsTheOscillationOfRr)
{
  const Eigen::Vector3d r(-5.0, 1.0, 4.0);
  LeverArm lever(r);
  const double rate = 50.0, f = 0.08, w = 2.0 * M_PI * f, trim = 0.05, amplitude = 0.06, yaw = 0.5;
  double error2 = 0.0, truth2 = 0.0, velocity_error2 = 0.0, velocity2 = 0.0;
  for (long i = 0; i < static_cast<long>(600 * rate); ++i)
  {
    const double t = i / rate;
    const double pitch = trim + amplitude * std::sin(w * t);
    const LeverArmOutput out = lever.update(attitude(0.0, pitch, yaw), i > 0 ? 1.0 / rate : 0.0);
    if (t < 300.0)
      continue;
    // R r less its value at the trim, to first order in the oscillation.
    const Eigen::Vector3d at_trim = attitude(0.0, trim, yaw) * r;
    const Eigen::Vector3d truth = attitude(0.0, pitch, yaw) * r - at_trim;
    const double rate_of_pitch = amplitude * w * std::cos(w * t);
    const Eigen::Vector3d truth_velocity = attitude(0.0, pitch, yaw).toRotationMatrix() *
                                           (Eigen::Vector3d(0.0, rate_of_pitch, 0.0).cross(r));  // body rate about y
    error2 += (out.position - truth).squaredNorm();
    truth2 += truth.squaredNorm();
    velocity_error2 += (out.velocity - truth_velocity).squaredNorm();
    velocity2 += truth_velocity.squaredNorm();
  }
  // Second-order terms of the oscillation (its mean over a period) and the slow means' error.
  EXPECT_LT(std::sqrt(error2 / truth2), 0.03);
  EXPECT_LT(std::sqrt(velocity_error2 / velocity2), 0.03);
}

// A standing heel while the ship turns: R r turns with the heading but has no wave part.
TEST(LeverArm, HeelInATurnIsNoWave)
{
  LeverArm lever(Eigen::Vector3d(-5.0, 1.0, 4.0));
  double largest = 0.0;
  for (long i = 0; i < 100 * 300; ++i)
  {
    const double t = i / 100.0;
    const LeverArmOutput out = lever.update(attitude(0.08, 0.02, 0.03 * t), i > 0 ? 0.01 : 0.0);
    largest = std::max(largest, out.position.norm());
  }
  EXPECT_LT(largest, 1e-9);
}
}  // namespace periodic_bias_compensation
