// ROS wrapper of the estimation core: topics, parameters, tf2, services, dynamic_reconfigure,
// diagnostics. The node (compensator_node) and the nodelet (CompensatorNodelet) only create it.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <boost/thread/recursive_mutex.hpp>

#include "periodic_bias_compensation/CompensatorConfig.h"
#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/raw_integrator.h"
#include "periodic_bias_compensation/ros/callback_thread.h"
#include "periodic_bias_compensation/ros/conversions.h"
#include "periodic_bias_compensation/ros/cpu_wakeup_latency.h"
#include "periodic_bias_compensation/ros/parameters.h"

namespace periodic_bias_compensation
{
/// dynamic_reconfigure parameters (cfg/Compensator.cfg).
using TuningConfig = periodic_bias_compensation_cfg::CompensatorConfig;

/// Subscribes imu/data, runs the Compensator, publishes odometry/filtered, odometry/wave,
/// bias_state, path/filtered, path/raw, optional TF and /diagnostics.
class CompensatorRos
{
public:
  /// Reads and validates the parameters of `pnh`, loads the calibration file if set, then
  /// advertises, subscribes and starts the services and the reconfigure server.
  /// @throws std::runtime_error with a message naming the key when a parameter is invalid;
  ///         nothing is subscribed or advertised then.
  CompensatorRos(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~CompensatorRos();
  CompensatorRos(const CompensatorRos&) = delete;
  CompensatorRos& operator=(const CompensatorRos&) = delete;

  /// The queue of the imu/data subscription. Deep: every dropped sample is a gap for the
  /// integration (1000 samples are 10 s at 100 Hz, enough to ride out a stall or a bag replayed
  /// faster than real time).
  static constexpr std::uint32_t kImuQueue = 1000;
  /// The queue of each per-sample publisher (odometry/filtered, odometry/wave, bias_state).
  static constexpr std::uint32_t kOutputQueue = 200;
  /// How imu/data is subscribed: over TCP without Nagle's delay (a sample is a small message).
  static ros::TransportHints imuTransport()
  {
    return ros::TransportHints().tcpNoDelay();
  }

private:
  /// Counters kept by the wrapper on top of the core's CompensatorCounters.
  struct WrapperCounters
  {
    std::uint64_t received = 0;               ///< messages on imu/data
    std::uint64_t rejected_wrong_frame = 0;   ///< frame_id differs from the expected one
    std::uint64_t waiting_for_mounting = 0;   ///< dropped while waiting for imu -> base tf
    std::uint64_t nonfinite_outputs = 0;      ///< outputs not published because not finite
    std::uint64_t rejected_out_of_range = 0;  ///< finite but implausible force/rate (plausible())
    std::uint64_t without_orientation = 0;    ///< accepted messages that carried no orientation
    std::uint64_t refused_reconfigures = 0;   ///< dynamic_reconfigure requests refused
  };

  enum class MountingState
  {
    kWaiting,   ///< no transform yet, samples dropped up to mount_timeout
    kFound,     ///< transform from tf2
    kIdentity,  ///< imu frame is the base frame
    kFallback,  ///< lookup timed out: identity, warned (throttled) and shown in diagnostics
  };

  void imuCallback(const sensor_msgs::Imu::ConstPtr& msg);
  /// Resolves the mounting; false while the sample must be dropped (still waiting).
  bool updateMounting(const sensor_msgs::Imu& msg);
  /// Stops listening to /tf once the mounting is decided (it is never looked up again).
  void releaseTransformListener();
  void publishOutputs(const sensor_msgs::Imu& msg, const CompensatorOutput& out, SampleStatus status);
  void appendPaths(const ros::Time& stamp, const CompensatorOutput& out);
  void clearPaths();
  void reconfigure(TuningConfig& config, uint32_t level);
  /// Writes the running configuration's run-time parameters into *config.
  void showRunningConfig(TuningConfig* config) const;
  bool calibrate(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool saveCalibration(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  /// The input's own faults for diagnose(): units, output stopped while input arrives.
  void diagnoseInput(const ros::Time& now, const std::function<void(std::uint8_t, const std::string&)>& raise) const;
  /// What changed since the last diagnose(): samples dropped, resets, refused reconfigures.
  void diagnoseEvents(const CompensatorCounters& core,
                      const std::function<void(std::uint8_t, const std::string&)>& raise) const;
  /// Standing conditions: orientation missing, paper-mode periods too short, identity mounting.
  void diagnoseSetup(const std::function<void(std::uint8_t, const std::string&)>& raise) const;
  /// The key-value pairs of the status.
  void addDiagnosticValues(diagnostic_updater::DiagnosticStatusWrapper& stat, const CompensatorCounters& core,
                           double interval) const;
  void diagnosticTimer(const ros::TimerEvent& event);

  // Threading rule: every callback (IMU, services, reconfigure, diagnostics timer) holds mutex_
  // for its whole duration, so the Compensator and all members below are only touched by one
  // thread at a time, also under a multi-threaded nodelet manager. The reconfigure server
  // shares mutex_ (it is recursive because the server calls back while holding it).
  boost::recursive_mutex mutex_;

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  Parameters params_;
  std::unique_ptr<Compensator> compensator_;
  std::string calibration_source_;  ///< where the constant bias came from, for diagnostics

  FrameFilter frame_filter_;
  Mounting mounting_;
  MountingState mounting_state_ = MountingState::kWaiting;
  ros::WallTime mounting_warned_;  ///< when the identity mounting was last said (WARN)
  double first_stamp_ = -1.0;      ///< stamp of the first message [s], for mount_timeout
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;  ///< until the mounting is decided
  std::thread listener_release_;                             ///< destroys tf_listener_ (releaseTransformListener)
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;

  CpuWakeupLatencyRequest cpu_wakeup_latency_;  ///< held when params_.ros.cpu_wakeup_latency >= 0
  std::unique_ptr<CallbackThread> imu_thread_;  ///< serves imu_sub_ when params_.ros.imu_thread
  ros::Subscriber imu_sub_;
  ros::Publisher filtered_pub_;
  ros::Publisher wave_pub_;
  ros::Publisher bias_pub_;
  ros::Publisher path_filtered_pub_;
  ros::Publisher path_raw_pub_;
  ros::ServiceServer calibrate_srv_;
  ros::ServiceServer save_srv_;
  std::unique_ptr<dynamic_reconfigure::Server<TuningConfig>> reconfigure_server_;
  bool first_reconfigure_ = true;

  RawIntegrator raw_;
  std::deque<geometry_msgs::PoseStamped> path_filtered_;
  std::deque<geometry_msgs::PoseStamped> path_raw_;
  double last_path_stamp_ = -1.0;  ///< [s]

  WrapperCounters counters_;
  bool has_output_ = false;
  CompensatorOutput last_output_;
  ros::Time last_receive_;         ///< ROS time of the last message on imu/data
  ros::Time last_publish_;         ///< ROS time of the last odometry published (zero: none yet)
  ros::Time first_receive_;        ///< ROS time of the first message on imu/data
  bool seen_orientation_ = false;  ///< some message carried an orientation
  bool has_orientation_ = false;   ///< the last accepted message carried one
  std::string last_refusal_;       ///< why the last reconfigure request was refused

  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Timer diagnostic_timer_;
  /// Snapshot at the previous diagnostics update, to report what happened since.
  CompensatorCounters diag_core_prev_;
  WrapperCounters diag_wrapper_prev_;
  ros::Time diag_prev_time_;
};

}  // namespace periodic_bias_compensation
