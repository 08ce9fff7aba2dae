// The ROS messages of one simulator sample, shared by simulate_imu (bag) and simulator_node (live)
// so that both publish exactly the same topics, frames and covariances (docs/simulator.md).
#pragma once

#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/Temperature.h>

#include "periodic_bias_compensation/sim/simulator.h"

namespace periodic_bias_compensation
{
/// Topic names of the simulator's output (relative, so a namespace can be pushed).
struct SimTopics
{
  static constexpr const char* kImu = "imu/data";
  static constexpr const char* kTemperature = "imu/temperature";
  static constexpr const char* kTruth = "ground_truth/odometry";
  static constexpr const char* kTruthSlow = "ground_truth/slow";
  static constexpr const char* kTruthWave = "ground_truth/wave";
};

/// Messages of one sample. `imu` and `temperature` are valid only when the flags say so (a dropped
/// sample has no IMU message; a scenario without a temperature profile has no temperature).
struct SimMessages
{
  bool has_imu = false;
  sensor_msgs::Imu imu;
  bool has_temperature = false;
  sensor_msgs::Temperature temperature;
  nav_msgs::Odometry truth, truth_slow, truth_wave;  ///< odom -> base_link, stamped with the sample time
};

/// Builds the messages of a scenario's samples. Frames: imu_link (IMU, temperature), odom ->
/// base_link (truth). Covariances come from the scenario's noise (sim::imuCovariance).
class SimMessageBuilder
{
public:
  explicit SimMessageBuilder(const sim::Scenario& scenario);

  /// Fills `out` from `sample` (header stamp: the sensor's stamp; truth stamps: the sample time).
  void build(const sim::Sample& sample, SimMessages* out) const;

private:
  sensor_msgs::Imu imu_template_;
};
}  // namespace periodic_bias_compensation
