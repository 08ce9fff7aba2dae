// Sim-to-real gap diagnosis (no ROS): an IMU recording in SI units, its ground truth, and the
// simulated recordings it is compared with. See docs/gap.md.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "periodic_bias_compensation/sim/scenario.h"

namespace periodic_bias_compensation::gap
{
constexpr int kChannels = 6;  ///< ax, ay, az [m/s^2], gx, gy, gz [rad/s]

/// "ax", "ay", "az", "gx", "gy", "gz".
const std::array<std::string, kChannels>& channelNames();

/// Ground truth of a recording (a nav_msgs/Odometry topic, or truth columns of a CSV), on its
/// own time base. World frame z up (ENU for a ship, the robot's base frame for an arm).
struct TruthTrack
{
  std::vector<double> stamp;                      ///< [s], the IMU's clock
  std::vector<Eigen::Vector3d> position;          ///< world [m]
  std::vector<Eigen::Quaterniond> orientation;    ///< body -> world
  bool has_twist = false;                         ///< velocities given (else differentiated)
  std::vector<Eigen::Vector3d> velocity;          ///< body frame [m/s] (odometry twist)
  std::vector<Eigen::Vector3d> angular_velocity;  ///< body frame [rad/s]

  std::size_t size() const
  {
    return stamp.size();
  }
};

/// An IMU recording in SI units (REP-145, sensor frame). Samples in stamp order as recorded.
struct Recording
{
  double rate = 0.0;          ///< nominal sample rate [Hz] (0: estimate from stamps)
  std::vector<double> stamp;  ///< reported time stamps [s]
  Eigen::MatrixXd data;       ///< N x 6: ax, ay, az [m/s^2], gx, gy, gz [rad/s]
  bool has_orientation = false;
  std::vector<Eigen::Quaterniond> orientation;  ///< reported sensor -> ENU
  bool has_temperature = false;
  std::vector<double> temperature;  ///< [degC]
  std::string source;               ///< file name or "sim seed N"
  TruthTrack truth;                 ///< empty when the recording has no truth

  std::size_t size() const
  {
    return stamp.size();
  }
};

/// The sample rate of the stamps [Hz]: the slope of fitStampLine started from the median
/// interval (0 with fewer than 2 samples).
double estimateRate(const Recording& recording);

/// Samples with stamp - stamp[0] in [from, to) * span (fractions of the recording's span).
Recording sliceFraction(const Recording& recording, double from, double to);

/// Runs the simulator and keeps what a real sensor would give (dropped samples removed), and with
/// keep_truth its truth (as ground_truth/odometry carries it) at every kept sample.
Recording simulateRecording(const sim::Scenario& scenario, std::uint64_t seed, bool keep_truth = false);

/// simulateRecording (without truth) of scenarios that differ only in their effects, on one seed,
/// the motion evaluated once for all: each recording is handed to `use` (variant index, recording)
/// as soon as it is made, and is the one simulateRecording would give. A variant whose scenario
/// cannot be simulated is skipped and its error returned.
/// @return per variant, the error that kept it from being simulated ("" when it was)
std::vector<std::string> simulateVariants(const std::vector<sim::Scenario>& scenarios, std::uint64_t seed,
                                          const std::function<void(int, Recording&)>& use);

/// A scenario made to match a recording: same rate, duration and start time.
sim::Scenario matchScenario(const sim::Scenario& scenario, const Recording& real);

}  // namespace periodic_bias_compensation::gap
