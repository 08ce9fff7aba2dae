// Ship IMU simulator: motion truth, ideal IMU, sensor effects, one sample at a time.
//
//   sim::Scenario s = sim::loadScenario(path);
//   sim::Simulator simulator(s, seed);
//   sim::Sample sample;
//   while (simulator.next(&sample)) { ... }
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "periodic_bias_compensation/sim/effects.h"
#include "periodic_bias_compensation/sim/motion.h"
#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation::sim
{
/// Diagonal covariances to publish with the IMU data (sensor_msgs/Imu).
struct ImuCovariance
{
  Vector3 accel_variance = Vector3::Zero();  ///< per-sample white noise and quantization [(m/s^2)^2]
  Vector3 gyro_variance = Vector3::Zero();   ///< [(rad/s)^2]
  double orientation_variance = 0.0;         ///< orientation_stddev^2 [rad^2]
};

/// Covariances implied by the enabled white_noise and quantization effects.
/// @param scenario validated scenario
ImuCovariance imuCovariance(const Scenario& scenario);

/// Sensor temperature of a profile.
/// @param profile temperature profile
/// @param elapsed time since start [s]
/// @return temperature [degC]
double temperatureAt(const TemperatureProfile& profile, double elapsed);

/// Specific force and angular rate an ideal IMU at base_link measures (REP-145).
/// @param truth exact motion
/// @param gravity [m/s^2]
/// @param accel specific force incl. gravity, body frame [m/s^2]
/// @param gyro angular rate, body frame [rad/s]
void idealImu(const Truth& truth, double gravity, Vector3* accel, Vector3* gyro);

/// One truth as nav_msgs/Odometry carries it: pose in ENU (frame odom), twist in the child
/// frame given by the orientation.
struct OdometryState
{
  Vector3 position = Vector3::Zero();               ///< ENU [m]
  Quaternion orientation = Quaternion::Identity();  ///< child -> ENU
  Vector3 linear_velocity = Vector3::Zero();        ///< child frame [m/s]
  Vector3 angular_velocity = Vector3::Zero();       ///< child frame [rad/s]
};

/// The truth as three odometries (ground_truth/odometry, ground_truth/slow,
/// ground_truth/wave). slow: slow position, heading-only orientation; wave: wave position with
/// the full attitude; positions add up: total = slow + wave.
struct TruthOdometry
{
  OdometryState total;
  OdometryState slow;
  OdometryState wave;
};

/// Splits a truth into the three published odometries.
/// @param truth exact motion
TruthOdometry truthOdometry(const Truth& truth);

/// Produces the samples of a scenario. The same scenario and seed give bit-identical samples.
/// Threading: a Simulator is not thread-safe; use one per thread (they share nothing).
class Simulator
{
public:
  /// @param scenario scenario (validated here)
  /// @param seed seed of every random stream [-]
  /// @param outputs what of the truth the samples carry (kSensor: what the sensor reads, faster)
  /// @throws std::runtime_error on an invalid scenario
  Simulator(const Scenario& scenario, std::uint64_t seed, ShipMotion::Outputs outputs = ShipMotion::Outputs::kAll);

  /// Produces the next sample.
  /// @param sample output (also filled for dropped samples, with dropped = true)
  /// @return false when the scenario is over (sample untouched)
  bool next(Sample* sample);

  /// Produces the next sample on a motion evaluated elsewhere, which one evaluation then serves
  /// for several sensors: `truth` is the next sample's truth of a Simulator whose scenario
  /// differs from this one's only in its effects, on the same seed. The sample is then the one
  /// next(Sample*) would give. Only the truth's attitude, acceleration, angular rate and angular
  /// acceleration reach the sensor.
  /// @param truth the motion at this simulator's next sample
  /// @param sample output (also filled for dropped samples, with dropped = true; its truth is `truth`)
  /// @return false when the scenario is over (sample untouched)
  bool next(const Truth& truth, Sample* sample);

  /// Total number of samples.
  std::int64_t sampleCount() const
  {
    return count_;
  }

  /// The scenario, effects completed with their defaults.
  const Scenario& scenario() const
  {
    return scenario_;
  }

  /// The motion model (e.g. for its wave components).
  const ShipMotion& motion() const
  {
    return motion_;
  }

private:
  Scenario scenario_;
  ShipMotion motion_;
  std::vector<std::unique_ptr<Effect>> effects_;
  std::int64_t count_;
  std::int64_t k_ = 0;
};
}  // namespace periodic_bias_compensation::sim
