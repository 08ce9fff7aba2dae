#include "periodic_bias_compensation/ros/compensator_ros.h"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <boost/make_shared.hpp>

#include "periodic_bias_compensation/core/calibration_file.h"
#include "periodic_bias_compensation/ros/mounting.h"

namespace periodic_bias_compensation
{
namespace
{
constexpr double kWarnPeriod = 5.0;  ///< throttle of hot-path warnings [s]
/// Input arriving with nothing published for this long is an ERROR in diagnostics [s].
constexpr double kNoOutputTime = 1.0;

bool fileExists(const std::string& path)
{
  return std::ifstream(path).good();
}

geometry_msgs::PoseStamped poseStamped(const std::string& frame, const ros::Time& stamp, const Vector3& position,
                                       const Quaternion& orientation)
{
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = frame;
  pose.header.stamp = stamp;
  pose.pose.position.x = position.x();
  pose.pose.position.y = position.y();
  pose.pose.position.z = position.z();
  pose.pose.orientation.w = orientation.w();
  pose.pose.orientation.x = orientation.x();
  pose.pose.orientation.y = orientation.y();
  pose.pose.orientation.z = orientation.z();
  return pose;
}

nav_msgs::Path toPath(const std::deque<geometry_msgs::PoseStamped>& poses, const std::string& frame,
                      const ros::Time& stamp)
{
  nav_msgs::Path path;
  path.header.frame_id = frame;
  path.header.stamp = stamp;
  path.poses.assign(poses.begin(), poses.end());
  return path;
}
}  // namespace

CompensatorRos::CompensatorRos(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh)
{
  // Timers, services and the subscription may fire on other threads before the constructor is done.
  boost::recursive_mutex::scoped_lock lock(mutex_);
  std::string why;
  if (!readParameters(RosParameterSource(pnh_), &params_, &why))
  {
    throw std::runtime_error(why);
  }
  compensator_ = std::make_unique<Compensator>(params_.core);
  calibration_source_ = "calibration window";
  const std::string& calibration_file = params_.ros.calibration_file;
  if (!calibration_file.empty())
  {
    if (fileExists(calibration_file))
    {
      Vector3 bias;
      bool loaded = false;
      try
      {
        loaded = loadCalibration(calibration_file, &bias, &why);
      }
      catch (const std::exception& e)
      {
        // Some malformed files make the YAML parser throw instead of returning false.
        why = "'" + calibration_file + "' is not a calibration file (" + e.what() + ")";
      }
      if (!loaded)
      {
        throw std::runtime_error("parameter 'calibration_file': " + why);
      }
      if (!compensator_->setConstantBias(bias))
      {
        throw std::runtime_error("parameter 'calibration_file': '" + calibration_file +
                                 "' holds a non-finite constant bias");
      }
      calibration_source_ = "file " + calibration_file;
      ROS_INFO("constant bias [%.5f %.5f %.5f] m/s^2 loaded from %s", bias.x(), bias.y(), bias.z(),
               calibration_file.c_str());
    }
    else
    {
      ROS_WARN(
          "calibration file %s does not exist: calibrating from the first %.1f s of data "
          "(call ~save_calibration to write it)",
          calibration_file.c_str(), params_.core.calibration_duration);
    }
  }
  frame_filter_ = FrameFilter(params_.ros.imu_frame);

  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  if (params_.ros.publish_tf)
  {
    tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  }

  filtered_pub_ = nh_.advertise<nav_msgs::Odometry>("odometry/filtered", kOutputQueue);
  wave_pub_ = nh_.advertise<nav_msgs::Odometry>("odometry/wave", kOutputQueue);
  bias_pub_ = nh_.advertise<BiasState>("bias_state", kOutputQueue);
  path_filtered_pub_ = nh_.advertise<nav_msgs::Path>("path/filtered", 1, true);
  path_raw_pub_ = nh_.advertise<nav_msgs::Path>("path/raw", 1, true);

  updater_ = std::make_unique<diagnostic_updater::Updater>(nh_, pnh_, pnh_.getNamespace());
  updater_->setHardwareID(frame_filter_.known() ? frame_filter_.expected() : std::string("imu"));
  updater_->add("bias compensation", this, &CompensatorRos::diagnose);
  diag_prev_time_ = ros::Time::now();
  diagnostic_timer_ =
      pnh_.createTimer(ros::Duration(params_.ros.diagnostic_period), &CompensatorRos::diagnosticTimer, this);

  calibrate_srv_ = pnh_.advertiseService("calibrate", &CompensatorRos::calibrate, this);
  save_srv_ = pnh_.advertiseService("save_calibration", &CompensatorRos::saveCalibration, this);

  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<TuningConfig>>(mutex_, pnh_);
  reconfigure_server_->setCallback([this](TuningConfig& config, uint32_t level) { reconfigure(config, level); });

  if (params_.ros.cpu_wakeup_latency >= 0.0)
  {
    std::string why;
    if (cpu_wakeup_latency_.request(params_.ros.cpu_wakeup_latency, &why))
      ROS_INFO("every CPU asked to wake within %g s while this node runs", params_.ros.cpu_wakeup_latency);
    else
      ROS_WARN("cpu_wakeup_latency %g s not applied, the CPUs keep their idle states: %s",
               params_.ros.cpu_wakeup_latency, why.c_str());
  }
  ros::SubscribeOptions imu_options;
  imu_options.init<sensor_msgs::Imu>("imu/data", kImuQueue,
                                     [this](const sensor_msgs::Imu::ConstPtr& msg) { imuCallback(msg); });
  imu_options.transport_hints = imuTransport();
  if (params_.ros.imu_thread)
  {
    imu_thread_ = std::make_unique<CallbackThread>("pbc_imu");
    imu_options.callback_queue = imu_thread_->queue();
    if (params_.ros.imu_thread_priority > 0)
    {
      std::string why;
      if (imu_thread_->setRealtimePriority(params_.ros.imu_thread_priority, &why))
        ROS_INFO("pbc_imu runs real-time (SCHED_FIFO, priority %d)", params_.ros.imu_thread_priority);
      else
        ROS_WARN("imu_thread_priority %d not applied, pbc_imu runs as an ordinary thread: %s",
                 params_.ros.imu_thread_priority, why.c_str());
    }
  }
  imu_sub_ = nh_.subscribe(imu_options);
  ROS_INFO("bias compensation (%s mode) listening on %s, publishing %s and %s", toString(params_.core.mode).c_str(),
           imu_sub_.getTopic().c_str(), filtered_pub_.getTopic().c_str(), wave_pub_.getTopic().c_str());
}

CompensatorRos::~CompensatorRos()
{
  // Samples stop first (one being handled on imu_thread_ is waited for): the members a sample
  // uses are declared after imu_sub_ and would be destroyed before it.
  imu_sub_.shutdown();
  if (listener_release_.joinable())
  {
    listener_release_.join();
  }
}

void CompensatorRos::imuCallback(const sensor_msgs::Imu::ConstPtr& msg)
{
  boost::recursive_mutex::scoped_lock lock(mutex_);
  ++counters_.received;
  last_receive_ = ros::Time::now();
  if (counters_.received == 1)
  {
    first_receive_ = last_receive_;
  }

  if (!frame_filter_.accept(msg->header.frame_id))
  {
    ++counters_.rejected_wrong_frame;
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "imu/data: frame_id '%s' is not the expected '%s': message dropped (%" PRIu64 " so far)",
                      msg->header.frame_id.c_str(), frame_filter_.expected().c_str(), counters_.rejected_wrong_frame);
    return;
  }
  if (!updateMounting(*msg))
  {
    ++counters_.waiting_for_mounting;
    return;
  }

  const ImuSample sample = toImuSample(*msg, mounting_);
  if (!plausible(sample))
  {
    ++counters_.rejected_out_of_range;
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "imu/data: sample at t = %.3f s dropped: acceleration or angular rate out of range "
                      "(|a| > %.0f m/s^2 or |w| > %.0f rad/s)",
                      sample.t, kMaxSpecificForce, kMaxAngularRate);
    return;
  }
  CompensatorOutput out;
  const std::uint64_t zero_orientation = compensator_->counters().zero_orientation;
  const SampleStatus status = compensator_->addSample(sample, &out);
  if (zero_orientation == 0 && compensator_->counters().zero_orientation > 0)
  {
    ROS_WARN("imu/data: all-zero orientation quaternion without the covariance -1 flag: taken as no orientation");
  }
  if (producedOutput(status))
  {
    if (!frame_filter_.known())
    {
      frame_filter_.learn(msg->header.frame_id);
      if (frame_filter_.known())
      {
        updater_->setHardwareID(frame_filter_.expected());
      }
    }
    // An all-zero quaternion counts as none (the core takes it so).
    const bool with_orientation =
        sample.has_orientation && compensator_->counters().zero_orientation == zero_orientation;
    has_orientation_ = with_orientation;
    seen_orientation_ = seen_orientation_ || with_orientation;
    if (!with_orientation)
    {
      ++counters_.without_orientation;
    }
  }
  switch (status)
  {
    case SampleStatus::kAccepted:
      break;
    case SampleStatus::kRejectedNonFinite:
    case SampleStatus::kRejectedBadQuaternion:
    case SampleStatus::kRejectedDuplicate:
    case SampleStatus::kRejectedOutOfRange:
    case SampleStatus::kRejectedEarly:
      ROS_WARN_THROTTLE(kWarnPeriod, "imu/data: sample at t = %.3f s dropped: %s", sample.t, toString(status).c_str());
      return;
    case SampleStatus::kHeld:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "imu/data: stamp t = %.3f s does not continue the stream: held until %d samples "
                        "confirm the jump, dropped if the stream goes on",
                        sample.t, kConfirmSamples);
      return;
    case SampleStatus::kResetBackwards:
      ROS_WARN_THROTTLE(kWarnPeriod, "imu/data: stamp went backwards (t = %.3f s): estimator and paths reset",
                        sample.t);
      raw_.reset();
      clearPaths();
      break;
    case SampleStatus::kGapReset:
      ROS_WARN_THROTTLE(kWarnPeriod, "imu/data: gap longer than max_gap = %.2f s before t = %.3f s: integration reset",
                        compensator_->config().max_gap, sample.t);
      break;
  }
  publishOutputs(*msg, out, status);
}

bool CompensatorRos::updateMounting(const sensor_msgs::Imu& msg)
{
  if (mounting_state_ != MountingState::kWaiting)
  {
    // Repeated once a minute of wall time after the first WARN (rosconsole's delayed throttle
    // starts from ros::Time, which jumps when a bag's clock starts: a second WARN at once).
    if (mounting_state_ == MountingState::kFallback &&
        ros::WallTime::now() - mounting_warned_ > ros::WallDuration(60.0))
    {
      mounting_warned_ = ros::WallTime::now();
      ROS_WARN("no transform %s -> %s: using the identity as IMU mounting", msg.header.frame_id.c_str(),
               params_.ros.base_frame.c_str());
    }
    return true;
  }
  const std::string& imu_frame = msg.header.frame_id;
  const MountingLookup lookup = lookupMounting(tf_buffer_, imu_frame, params_.ros);
  mounting_ = lookup.mounting;
  switch (lookup.source)
  {
    case MountingSource::kNotNeeded:
      mounting_state_ = MountingState::kIdentity;
      releaseTransformListener();
      return true;
    case MountingSource::kTransform:
      mounting_state_ = MountingState::kFound;
      ROS_INFO("IMU mounting %s -> %s: %s", imu_frame.c_str(), params_.ros.base_frame.c_str(),
               describeMounting(mounting_).c_str());
      releaseTransformListener();
      return true;
    case MountingSource::kMissing:
      break;
  }
  const double t = msg.header.stamp.toSec();
  if (first_stamp_ < 0.0 || t < first_stamp_)
  {
    first_stamp_ = t;
  }
  if (t - first_stamp_ < params_.ros.mount_timeout)
  {
    ROS_INFO_THROTTLE(1.0, "waiting for the transform %s -> %s", imu_frame.c_str(), params_.ros.base_frame.c_str());
    return false;
  }
  mounting_state_ = MountingState::kFallback;
  releaseTransformListener();
  mounting_warned_ = ros::WallTime::now();
  ROS_WARN("no transform %s -> %s after %.1f s (%s): using the identity as IMU mounting", imu_frame.c_str(),
           params_.ros.base_frame.c_str(), params_.ros.mount_timeout, lookup.why.c_str());
  return true;
}

void CompensatorRos::releaseTransformListener()
{
  // The mounting is looked up once. Listening on after that would only cost a thread wake-up per
  // message of /tf, this node's own transform among them (one per IMU sample). Destroying the
  // listener joins its thread, which takes milliseconds: done on a thread of its own, not in the
  // IMU callback.
  if (!tf_listener_ || listener_release_.joinable())
  {
    tf_listener_.reset();
    return;
  }
  listener_release_ = std::thread([listener = std::move(tf_listener_)]() mutable { listener.reset(); });
}

void CompensatorRos::publishOutputs(const sensor_msgs::Imu& msg, const CompensatorOutput& out, SampleStatus status)
{
  const ros::Time& stamp = msg.header.stamp;
  const OdometryFrames frames{ params_.ros.odom_frame, params_.ros.base_frame };
  // Published as shared pointers: a subscriber in the same process (a nodelet) gets them from this
  // thread without a copy; a message published by value would be serialized and handed over by
  // roscpp's poll thread, a thread wake-up more per message.
  const auto filtered =
      boost::make_shared<nav_msgs::Odometry>(toOdometry(out, OdometryKind::kFiltered, msg, mounting_, frames, stamp));
  const auto wave =
      boost::make_shared<nav_msgs::Odometry>(toOdometry(out, OdometryKind::kWave, msg, mounting_, frames, stamp));
  const auto bias =
      boost::make_shared<BiasState>(toBiasState(out, compensator_->config().mode, params_.ros.odom_frame, stamp));
  if (!allFinite(*filtered) || !allFinite(*wave) || !allFinite(*bias) || !out.acceleration_level.allFinite())
  {
    ++counters_.nonfinite_outputs;
    ROS_ERROR_THROTTLE(kWarnPeriod, "estimator output at t = %.3f s is not finite: not published (%" PRIu64 " so far)",
                       out.t, counters_.nonfinite_outputs);
    return;
  }
  filtered_pub_.publish(filtered);
  wave_pub_.publish(wave);
  bias_pub_.publish(bias);
  if (tf_broadcaster_)
  {
    geometry_msgs::TransformStamped tf;
    tf.header = filtered->header;
    tf.child_frame_id = filtered->child_frame_id;
    tf.transform.translation.x = filtered->pose.pose.position.x;
    tf.transform.translation.y = filtered->pose.pose.position.y;
    tf.transform.translation.z = filtered->pose.pose.position.z;
    tf.transform.rotation = filtered->pose.pose.orientation;
    tf_broadcaster_->sendTransform(tf);
  }
  has_output_ = true;
  last_publish_ = ros::Time::now();
  last_output_ = out;
  // Raw track: the gravity-free level acceleration with only the calibrated constant bias
  // removed (CompensatorOutput::acceleration_constant_compensated), integrated twice here.
  raw_.add(out.t, out.acceleration_constant_compensated, status == SampleStatus::kGapReset);
  appendPaths(stamp, out);
}

void CompensatorRos::appendPaths(const ros::Time& stamp, const CompensatorOutput& out)
{
  const double t = stamp.toSec();
  if (last_path_stamp_ >= 0.0 && t - last_path_stamp_ < 1.0 / params_.ros.path_rate)
  {
    return;
  }
  last_path_stamp_ = t;
  const Quaternion q = out.orientation.normalized();
  path_filtered_.push_back(poseStamped(params_.ros.odom_frame, stamp, out.position_filtered, q));
  path_raw_.push_back(poseStamped(params_.ros.odom_frame, stamp, raw_.position(), q));
  const auto max_length = static_cast<std::size_t>(params_.ros.path_max_length);
  while (path_filtered_.size() > max_length)
  {
    path_filtered_.pop_front();
  }
  while (path_raw_.size() > max_length)
  {
    path_raw_.pop_front();
  }
  if (path_filtered_pub_.getNumSubscribers() > 0)
  {
    path_filtered_pub_.publish(toPath(path_filtered_, params_.ros.odom_frame, stamp));
  }
  if (path_raw_pub_.getNumSubscribers() > 0)
  {
    path_raw_pub_.publish(toPath(path_raw_, params_.ros.odom_frame, stamp));
  }
}

void CompensatorRos::clearPaths()
{
  path_filtered_.clear();
  path_raw_.clear();
  last_path_stamp_ = -1.0;
}

void CompensatorRos::reconfigure(TuningConfig& config, uint32_t /*level*/)
{
  boost::recursive_mutex::scoped_lock lock(mutex_);
  if (first_reconfigure_)
  {
    // The server's first call carries what it read from the parameter server; the start-up
    // parameters, already validated, win and are shown to clients.
    first_reconfigure_ = false;
    showRunningConfig(&config);
    return;
  }
  const CompensatorConfig before = compensator_->config();
  CompensatorConfig next = before;
  dynamic_reconfigure::Config request;
  config.__toMessage__(request);
  std::string why;
  const bool applied = applyTuning(request, &next, &why) && compensator_->setConfig(next, &why);
  const std::vector<ParameterChange> changed = changes(compensatorParameters(), before, next);
  if (!applied)
  {
    std::string names;
    for (const ParameterChange& change : changed)
    {
      names += (names.empty() ? " of " : ", ") + change.info->key;
    }
    ROS_WARN("reconfigure%s refused, keeping the previous parameters: %s", names.c_str(), why.c_str());
    ++counters_.refused_reconfigures;
    last_refusal_ = why;
    // The server stores and returns the config it handed us: writing the running values back
    // makes the client see the refusal (the same effect as updateConfig, without re-entering).
    showRunningConfig(&config);
    return;
  }
  for (const ParameterChange& change : changed)
  {
    ROS_INFO("reconfigure: %s %s -> %s", change.info->key.c_str(), toString(change.before).c_str(),
             toString(change.after).c_str());
  }
  params_.core = compensator_->config();
}

void CompensatorRos::showRunningConfig(TuningConfig* config) const
{
  dynamic_reconfigure::Config message;
  config->__toMessage__(message);
  toTuning(compensator_->config(), &message);
  config->__fromMessage__(message);
}

bool CompensatorRos::calibrate(std_srvs::Trigger::Request& /*req*/, std_srvs::Trigger::Response& res)
{
  boost::recursive_mutex::scoped_lock lock(mutex_);
  compensator_->recalibrate();
  calibration_source_ = "calibration window";
  std::ostringstream message;
  message << "constant-bias calibration restarts at the next sample and uses " << params_.core.calibration_duration
          << " s of data" << (params_.core.assume_static_calibration ? "; keep the sensor still until then" : "")
          << "; call ~save_calibration afterwards to store it";
  res.success = true;
  res.message = message.str();
  ROS_INFO("%s", res.message.c_str());
  return true;
}

bool CompensatorRos::saveCalibration(std_srvs::Trigger::Request& /*req*/, std_srvs::Trigger::Response& res)
{
  boost::recursive_mutex::scoped_lock lock(mutex_);
  const std::string& path = params_.ros.calibration_file;
  res.success = false;
  if (path.empty())
  {
    res.message = "parameter ~calibration_file is not set: nothing written";
  }
  else if (!compensator_->calibrated())
  {
    res.message = "not calibrated yet (calibration window still running): nothing written";
  }
  else
  {
    std::string why;
    const Vector3 bias = compensator_->constantBias();
    if (periodic_bias_compensation::saveCalibration(path, bias, &why))
    {
      res.success = true;
      std::ostringstream message;
      message << "constant bias [" << bias.x() << ", " << bias.y() << ", " << bias.z() << "] m/s^2 written to " << path;
      res.message = message.str();
    }
    else
    {
      res.message = why;
    }
  }
  if (res.success)
  {
    ROS_INFO("%s", res.message.c_str());
  }
  else
  {
    ROS_WARN("save_calibration: %s", res.message.c_str());
  }
  return true;
}

void CompensatorRos::diagnoseInput(const ros::Time& now,
                                   const std::function<void(std::uint8_t, const std::string&)>& raise) const
{
  using diagnostic_msgs::DiagnosticStatus;
  const ForceUnits units = compensator_->forceUnits();
  if (units == ForceUnits::kLooksLikeG || units == ForceUnits::kImplausible)
  {
    char text[200];
    std::snprintf(text, sizeof text, "mean specific force %.3f against gravity %.3f m/s^2: %s",
                  compensator_->meanSpecificForce(), compensator_->config().gravity, toString(units).c_str());
    raise(DiagnosticStatus::ERROR, text);
  }
  // Input arriving while nothing is published: every sample refused, or held for a jump.
  const double receiving = (now - last_receive_).toSec();
  const double quiet = (now - (has_output_ ? last_publish_ : first_receive_)).toSec();
  if (counters_.received > 0 && receiving < kNoOutputTime && quiet > kNoOutputTime)
  {
    char text[120];
    std::snprintf(text, sizeof text, "imu/data arrives but nothing was published for %.1f s", quiet);
    raise(DiagnosticStatus::ERROR, text);
  }
}

void CompensatorRos::diagnosticTimer(const ros::TimerEvent& /*event*/)
{
  boost::recursive_mutex::scoped_lock lock(mutex_);
  updater_->force_update();
}

namespace
{
std::uint64_t countSince(std::uint64_t now_count, std::uint64_t prev_count)
{
  return now_count - prev_count;
}
}  // namespace

void CompensatorRos::diagnoseEvents(const CompensatorCounters& core,
                                    const std::function<void(std::uint8_t, const std::string&)>& raise) const
{
  using diagnostic_msgs::DiagnosticStatus;
  const std::uint64_t bad_outputs = countSince(counters_.nonfinite_outputs, diag_wrapper_prev_.nonfinite_outputs);
  if (bad_outputs > 0)
  {
    raise(DiagnosticStatus::ERROR, std::to_string(bad_outputs) + " non-finite outputs suppressed");
  }
  std::vector<std::string> rejected;
  auto count = [&rejected](std::uint64_t n, const std::string& what) {
    if (n > 0)
    {
      rejected.push_back(std::to_string(n) + " " + what);
    }
  };
  count(countSince(core.rejected_non_finite, diag_core_prev_.rejected_non_finite), "non-finite");
  count(countSince(core.rejected_bad_quaternion, diag_core_prev_.rejected_bad_quaternion), "bad quaternion");
  count(countSince(core.rejected_duplicate, diag_core_prev_.rejected_duplicate), "duplicate stamp");
  count(countSince(core.timing_glitches, diag_core_prev_.timing_glitches), "stamp glitch (early or out of order)");
  count(countSince(counters_.rejected_wrong_frame, diag_wrapper_prev_.rejected_wrong_frame), "wrong frame_id");
  count(countSince(counters_.rejected_out_of_range, diag_wrapper_prev_.rejected_out_of_range),
        "acceleration or angular rate out of range");
  if (!rejected.empty())
  {
    std::string joined = "samples dropped: ";
    for (std::size_t i = 0; i < rejected.size(); ++i)
    {
      joined += (i > 0 ? ", " : "") + rejected[i];
    }
    raise(DiagnosticStatus::WARN, joined);
  }
  if (countSince(core.resets_backwards, diag_core_prev_.resets_backwards) > 0)
  {
    raise(DiagnosticStatus::WARN, "time went backwards: estimator reset");
  }
  if (countSince(core.gap_resets, diag_core_prev_.gap_resets) > 0)
  {
    raise(DiagnosticStatus::WARN, "gap in IMU data: integration reset");
  }
  if (countSince(core.rate_changes, diag_core_prev_.rate_changes) > 0)
  {
    raise(DiagnosticStatus::WARN, "IMU sample rate changed: period search restarted");
  }
  if (countSince(counters_.refused_reconfigures, diag_wrapper_prev_.refused_reconfigures) > 0)
  {
    raise(DiagnosticStatus::WARN, "reconfigure refused, previous parameters kept: " + last_refusal_);
  }
}

void CompensatorRos::diagnoseSetup(const std::function<void(std::uint8_t, const std::string&)>& raise) const
{
  using diagnostic_msgs::DiagnosticStatus;
  if (seen_orientation_ && !has_orientation_ && counters_.received > 0)
  {
    const LevelSource source = compensator_->levelSource();
    raise(DiagnosticStatus::WARN,
          "IMU orientation missing: levelling with the " + toString(source) +
              (source == LevelSource::kGyroAttitude ? "" : " (roll and pitch of the hull leak into the level axes)"));
  }
  for (int i = 0; i < 3; ++i)
  {
    if (has_output_ && last_output_.axes[i].period_too_short)
    {
      char text[200];
      std::snprintf(text, sizeof text,
                    "period of %.1f samples on %s is shorter than %d: paper-mode periodic correction off there "
                    "(raise the IMU rate or lower max_frequency)",
                    last_output_.axes[i].period_samples, kAxisNames[i], kMinPaperPeriod);
      raise(DiagnosticStatus::WARN, text);
    }
  }
  if (mounting_state_ == MountingState::kFallback)
  {
    raise(DiagnosticStatus::WARN,
          "no transform " + frame_filter_.expected() + " -> " + params_.ros.base_frame + ": identity mounting assumed");
  }
}

void CompensatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  boost::recursive_mutex::scoped_lock lock(mutex_);
  using diagnostic_msgs::DiagnosticStatus;
  const ros::Time now = ros::Time::now();
  const CompensatorCounters& core = compensator_->counters();
  const double interval = (now - diag_prev_time_).toSec();

  std::uint8_t level = DiagnosticStatus::OK;
  std::vector<std::string> messages;
  auto raise = [&level, &messages](std::uint8_t l, const std::string& message) {
    level = std::max(level, l);
    messages.push_back(message);
  };

  if (counters_.received == 0)
  {
    raise(DiagnosticStatus::WARN, "waiting for IMU data on " + imu_sub_.getTopic());
  }
  else
  {
    const double silence = (now - last_receive_).toSec();
    if (silence > std::max(2.0, 3.0 * params_.ros.diagnostic_period))
    {
      std::ostringstream m;
      m.precision(1);
      m << std::fixed << "no IMU data for " << silence << " s";
      raise(DiagnosticStatus::ERROR, m.str());
    }
  }
  diagnoseInput(now, raise);
  diagnoseEvents(core, raise);
  diagnoseSetup(raise);
  // The outputs stay held after the window while it is processed again (calibrated by then).
  const bool held = has_output_ && last_output_.state == OutputState::kCalibrating;
  if (counters_.received > 0 && (!compensator_->calibrated() || held))
  {
    // Normal at start-up: shown, not raised.
    messages.push_back("calibrating constant bias (odometry held at zero meanwhile)");
  }
  // Period search: "no period" is normal on a calm sea, constant or pure-noise input (a lock
  // needs a peak min_peak_ratio times the median of the band); shown, not an error.
  bool any_locked = false;
  for (int i = 0; i < 3; ++i)
  {
    any_locked = any_locked || (has_output_ && last_output_.axes[i].locked);
  }
  if (messages.empty())
  {
    messages.push_back(any_locked ? "compensating" : "compensating; no period (no dominant wave period found)");
  }
  std::string summary;
  for (std::size_t i = 0; i < messages.size(); ++i)
  {
    summary += (i > 0 ? "; " : "") + messages[i];
  }
  stat.summary(level, summary);
  addDiagnosticValues(stat, core, interval);

  diag_core_prev_ = core;
  diag_wrapper_prev_ = counters_;
  diag_prev_time_ = now;
}

void CompensatorRos::addDiagnosticValues(diagnostic_updater::DiagnosticStatusWrapper& stat,
                                         const CompensatorCounters& core, double interval) const
{
  stat.add("mode", toString(compensator_->config().mode));
  stat.add("input topic", imu_sub_.getTopic());
  stat.add("input frame", frame_filter_.known() ? frame_filter_.expected() : std::string("(not seen yet)"));
  stat.addf("input rate [Hz]", "%.2f",
            interval > 0.0 ? static_cast<double>(countSince(counters_.received, diag_wrapper_prev_.received)) / interval
                           : 0.0);
  stat.addf("estimated sample rate [Hz]", "%.2f", core.sample_rate);
  stat.add("received", counters_.received);
  stat.add("accepted", core.accepted);
  stat.add("rejected non-finite", core.rejected_non_finite);
  stat.add("rejected bad quaternion", core.rejected_bad_quaternion);
  stat.add("rejected duplicate stamp", core.rejected_duplicate);
  stat.add("dropped stamp glitches", core.timing_glitches);
  stat.add("rejected wrong frame", counters_.rejected_wrong_frame);
  stat.add("dropped waiting for mounting", counters_.waiting_for_mounting);
  stat.add("backwards resets", core.resets_backwards);
  stat.add("gap resets", core.gap_resets);
  stat.add("sample rate changes", core.rate_changes);
  stat.add("non-finite outputs suppressed", counters_.nonfinite_outputs);
  stat.add("rejected out of range", counters_.rejected_out_of_range);
  stat.add("accepted without orientation", counters_.without_orientation);
  std::string orientation = "no input yet";
  if (counters_.received > 0 && has_orientation_)
    orientation = "from the IMU message";
  else if (counters_.received > 0)
    orientation = std::string(seen_orientation_ ? "missing" : "none in the input") +
                  (compensator_->levelSource() == LevelSource::kNone
                       ? ": not levelled yet"
                       : ": levelled with the " + toString(compensator_->levelSource()));
  stat.add("orientation", orientation);
  if (compensator_->levelSource() == LevelSource::kGyroAttitude)
  {
    const Vector3 b = compensator_->gyroBias();
    char text[100];
    std::snprintf(text, sizeof text, "%.6f %.6f %.6f", b.x(), b.y(), b.z());
    stat.add("gyro bias estimate x y z [rad/s]", std::string(text));
  }
  stat.add("refused reconfigures", counters_.refused_reconfigures);
  if (!last_refusal_.empty())
  {
    stat.add("last refused reconfigure", last_refusal_);
  }
  const char* mounting_names[] = { "waiting for tf", "from tf",
                                   "identity (imu frame is base frame, or identity_mounting)",
                                   "identity (tf lookup failed)" };
  stat.add("mounting", mounting_names[static_cast<int>(mounting_state_)]);
  stat.add("calibration", compensator_->calibrated() ? "done (" + calibration_source_ + ")" : std::string("running"));
  const Vector3 bias = compensator_->constantBias();
  stat.addf("constant bias [m/s^2]", "%.5f %.5f %.5f", bias.x(), bias.y(), bias.z());
  for (int i = 0; i < 3; ++i)
  {
    const std::string key = std::string("period lock ") + kAxisNames[i];
    if (has_output_ && last_output_.axes[i].locked)
    {
      stat.addf(key, "locked, %.3f Hz (L = %.1f samples)", last_output_.axes[i].frequency,
                last_output_.axes[i].period_samples);
    }
    else
    {
      stat.add(key, "no period");
    }
  }
}

}  // namespace periodic_bias_compensation
