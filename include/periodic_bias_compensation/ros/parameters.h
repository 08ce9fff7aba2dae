// Parameters of the compensator, read with the same keys from the ROS parameter server (node,
// nodelet) and from a YAML file (compensate_bag), and changed at run time through
// dynamic_reconfigure. The keys are those of two tables: compensatorParameters() (the core's
// CompensatorConfig) and rosOptionParameters() (RosOptions below); docs/ros_api.md lists them.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <dynamic_reconfigure/Config.h>
#include <ros/node_handle.h>
#include <yaml-cpp/yaml.h>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/parameter_table.h"

namespace periodic_bias_compensation
{
/// Settings of the ROS side (frames, outputs, start-up).
struct RosOptions
{
  std::string odom_frame = "odom";       ///< frame of the published odometry
  std::string base_frame = "base_link";  ///< child frame of the odometry, target of the mounting
  std::string imu_frame;                 ///< required frame_id of imu/data; empty = first one seen
  bool publish_tf = false;               ///< broadcast odom -> base_frame from odometry/filtered
  int path_max_length = 2000;            ///< poses kept in path/filtered and path/raw [-]
  double path_rate = 2.0;                ///< rate of path poses and path messages [Hz]
  double mount_timeout = 1.0;            ///< wait for the imu -> base transform (message time) [s]
  bool identity_mounting = false;        ///< the IMU is mounted aligned with base_frame: no lookup
  std::string calibration_file;          ///< constant-bias YAML; loaded at start when it exists
  double diagnostic_period = 1.0;        ///< period of /diagnostics (read by diagnostic_updater) [s]
  bool imu_thread = true;                ///< imu/data served by a thread of its own (CallbackThread)
  int imu_thread_priority = 0;           ///< SCHED_FIFO priority of that thread; 0: ordinary
  double cpu_wakeup_latency = -1.0;      ///< wake-up latency asked of every CPU [s]; < 0: none

  /// False with a message naming the key when a value is out of range (rosOptionParameters())
  /// or odom_frame equals base_frame, or imu_thread_priority is set without imu_thread.
  bool validate(std::string* why) const;
};

/// Every key of RosOptions, in the order of config/compensator.yaml.
const ParameterTable<RosOptions>& rosOptionParameters();

/// Everything read at start-up.
struct Parameters
{
  CompensatorConfig core;
  RosOptions ros;
};

/// Key/value store the parameters are read from.
class ParameterSource
{
public:
  virtual ~ParameterSource() = default;
  /// All keys present (top level).
  virtual std::vector<std::string> keys() const = 0;
  /// Typed reads of a present key; false with a message in *why on a type mismatch.
  virtual bool getBool(const std::string& key, bool* value, std::string* why) const = 0;
  virtual bool getInt(const std::string& key, int* value, std::string* why) const = 0;
  virtual bool getDouble(const std::string& key, double* value, std::string* why) const = 0;
  virtual bool getString(const std::string& key, std::string* value, std::string* why) const = 0;
};

/// Reads the keys present in `source` over the defaults already in *params. An unknown key, a
/// wrong type or an invalid value (core CompensatorConfig::validate, RosOptions::validate) gives
/// false with a message naming the key; *params is then unspecified.
bool readParameters(const ParameterSource& source, Parameters* params, std::string* why);

/// dynamic_reconfigure (cfg/Compensator.cfg declares the run-time keys of compensatorParameters()
/// with the table's defaults and ranges; test_ros_conversions checks that it does).
/// Writes every value of a request into *config. False with a message naming the key for a key
/// that is not a run-time parameter of the table, a value of another type or an unknown mode;
/// *config is then partly written. Ranges are left to CompensatorConfig::validate.
bool applyTuning(const dynamic_reconfigure::Config& request, CompensatorConfig* config, std::string* why);
/// The inverse: the run-time parameters of `config` written over the values in *message.
void toTuning(const CompensatorConfig& config, dynamic_reconfigure::Config* message);

/// The private namespace of a node or nodelet on the parameter server.
class RosParameterSource : public ParameterSource
{
public:
  /// @throws std::runtime_error when the namespace holds something other than key/value pairs
  explicit RosParameterSource(const ros::NodeHandle& pnh);
  std::vector<std::string> keys() const override;
  bool getBool(const std::string& key, bool* value, std::string* why) const override;
  bool getInt(const std::string& key, int* value, std::string* why) const override;
  bool getDouble(const std::string& key, double* value, std::string* why) const override;
  bool getString(const std::string& key, std::string* value, std::string* why) const override;

private:
  XmlRpc::XmlRpcValue values_;
  std::string ns_;
};

/// A YAML file whose top level is a map with the same keys.
class YamlParameterSource : public ParameterSource
{
public:
  /// @throws std::runtime_error naming the file when it cannot be read or is not a map
  explicit YamlParameterSource(const std::string& path);
  std::vector<std::string> keys() const override;
  bool getBool(const std::string& key, bool* value, std::string* why) const override;
  bool getInt(const std::string& key, int* value, std::string* why) const override;
  bool getDouble(const std::string& key, double* value, std::string* why) const override;
  bool getString(const std::string& key, std::string* value, std::string* why) const override;

private:
  YAML::Node root_;
  std::string path_;
};

}  // namespace periodic_bias_compensation
