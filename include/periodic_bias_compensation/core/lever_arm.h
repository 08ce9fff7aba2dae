// The motion of the point the outputs describe, not of the IMU (estimation core, no ROS).
//
// An IMU mounted at `r` from that point (body frame of the samples, usually base_link's origin
// or the ship's centre of gravity) moves by R r more than the point, R its attitude: a pitch of
// 3 degrees 5 m aft is 0.26 m of heave, a roll of 5 degrees 4 m up 0.35 m of sway. Motion
// reference units call taking it off "remote heave". The wave part of R r is its tilt's part,
// in a frame that turns with the heading (a turn moves R r slowly, which is not wave), less its
// slow part (two moving means of kTiltMemory in cascade: the trim and any standing heel, with an
// error of 1 / (1 + (omega kTiltMemory)^2) at the wave frequency omega, 0.5 % at 13 s): that is
// what the wave outputs lose.
// The yaw oscillation's part (yaw changes R r horizontally) is left in: it is small on a ship
// and cannot be told from a turn within a wave period.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <Eigen/Geometry>

namespace periodic_bias_compensation
{
struct LeverArmOutput
{
  Eigen::Vector3d position{ 0, 0, 0 };  ///< wave part of R r, level frame [m]
  Eigen::Vector3d velocity{ 0, 0, 0 };  ///< its rate [m/s]
};

class LeverArm
{
public:
  /// Time constant of each of the two means of the tilt displacement taken as standing (trim,
  /// heel) [s].
  static constexpr double kTiltMemory = 30.0;

  /// offset: the IMU's position from the point the outputs describe, body frame [m].
  explicit LeverArm(const Eigen::Vector3d& offset = Eigen::Vector3d::Zero());
  void setOffset(const Eigen::Vector3d& offset);
  const Eigen::Vector3d& offset() const
  {
    return offset_;
  }
  /// Whether there is anything to take off (a non-zero offset).
  bool active() const
  {
    return !offset_.isZero();
  }
  void reset();
  /// orientation: body -> level frame of this sample; dt: since the previous sample [s] (0 for
  /// the first).
  LeverArmOutput update(const Eigen::Quaterniond& orientation, double dt);

private:
  Eigen::Vector3d offset_;
  Eigen::Vector3d mean_{ 0, 0, 0 };      ///< of the tilt displacement, heading frame
  Eigen::Vector3d slow_{ 0, 0, 0 };      ///< mean of mean_: the slow part
  Eigen::Vector3d previous_{ 0, 0, 0 };  ///< last wave part, heading frame
  double samples_ = 0.0;
};
}  // namespace periodic_bias_compensation
