// Conversions between ROS messages and the estimation core, shared by the ROS wrapper
// (CompensatorRos) and the offline tool (compensate_bag). No NodeHandle, no master needed.
#pragma once

#include <string>

#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>
#include <boost/array.hpp>

#include "periodic_bias_compensation/BiasState.h"
#include "periodic_bias_compensation/core/compensator.h"

namespace periodic_bias_compensation
{
/// Covariance put on the diagonal of a quantity the input does not provide [rad^2 or (rad/s)^2].
constexpr double kUnknownCovariance = 1e3;

/// Mounting of the IMU on the vehicle: rotation taking vectors from the IMU frame to the base
/// frame. The lever arm is not used (rotations of the hull make it a small, zero-mean
/// acceleration that ends up in the wave estimate).
struct Mounting
{
  Quaternion imu_to_base{ 1, 0, 0, 0 };
};

/// Converts a sensor_msgs/Imu into a core sample expressed in the base frame.
/// t = header.stamp [s]; specific force and angular rate rotated by the mounting; the orientation
/// (imu -> level) is used when orientation_covariance[0] != -1 (REP-145) and turned into
/// base -> level. NaN/Inf are passed through on purpose: the core rejects and counts them.
ImuSample toImuSample(const sensor_msgs::Imu& msg, const Mounting& mounting);

/// True when the finite specific force and angular rate of a sample are physically plausible
/// (each component within the core's kMaxSpecificForce / kMaxAngularRate, which the core
/// enforces too; checked here to count and report them per message). NaN/Inf are left to the core
/// (this returns true for them) so that they keep their own counter. A finite but absurd value
/// (1e30 m/s^2) would otherwise be integrated and overflow the estimator state.
bool plausible(const ImuSample& sample);

/// Which of the two published motions an Odometry message carries.
enum class OdometryKind
{
  kFiltered,  ///< slow motion, drift and wave removed (odometry/filtered)
  kWave,      ///< periodic motion about the slow motion, drift-free (odometry/wave)
};

/// Frames of the published odometry.
struct OdometryFrames
{
  std::string odom_frame = "odom";       ///< header.frame_id (level ENU frame of the core)
  std::string base_frame = "base_link";  ///< child_frame_id
};

/// Builds odometry/filtered or odometry/wave from one core output.
/// Pose in the odom (level) frame, twist in the base frame (nav_msgs convention).
/// Covariances: position variances of the output on the diagonal; orientation and angular-rate
/// covariances from the IMU message rotated into the base frame, or kUnknownCovariance on the
/// diagonal when the message marks them unknown (all zeros) or absent (-1). Never -1.
/// @param imu the message that produced the output (angular rate and covariances)
nav_msgs::Odometry toOdometry(const CompensatorOutput& out, OdometryKind kind, const sensor_msgs::Imu& imu,
                              const Mounting& mounting, const OdometryFrames& frames, const ros::Time& stamp);

/// Builds the BiasState message (level frame) from one core output.
BiasState toBiasState(const CompensatorOutput& out, Mode mode, const std::string& odom_frame, const ros::Time& stamp);

/// True when every floating-point field that is published is finite.
bool allFinite(const nav_msgs::Odometry& msg);
bool allFinite(const BiasState& msg);

/// Accepts IMU messages from one frame only. Without an expected frame every frame passes until
/// learn() is told the frame of a message that was used (an empty frame_id is never learnt); that
/// frame is required from then on.
class FrameFilter
{
public:
  explicit FrameFilter(const std::string& expected = std::string()) : expected_(expected), fixed_(!expected.empty())
  {
  }
  /// True if the message frame is the expected one, or none is known yet.
  bool accept(const std::string& frame_id) const;
  /// Requires frame_id from now on, unless a frame is known already or it is empty.
  void learn(const std::string& frame_id);
  /// The frame required from now on; empty before the first message when none was configured.
  const std::string& expected() const
  {
    return expected_;
  }
  bool known() const
  {
    return fixed_;
  }

private:
  std::string expected_;
  bool fixed_;
};

}  // namespace periodic_bias_compensation
