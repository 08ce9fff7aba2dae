// Bad input through the real topic: crafted sensor_msgs/Imu on imu/data (NaN/Inf, non-unit
// quaternions, wrong frame_id, duplicated stamps, lone stamp glitches, stamps going backwards,
// a gap, a changed sample rate, no orientation). Asserts that nothing non-finite is ever
// published, that /diagnostics counts every case, that valid output keeps coming afterwards, and
// that the status turns to ERROR when the input stops.
// Also checks the optional outputs: TF odom -> base_link, path/filtered and path/raw bounded by
// path_max_length.
// Private parameters: record_path, a bag that launch/record.launch must be writing;
// path_max_length, as given to the compensator.
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "periodic_bias_compensation/BiasState.h"

namespace
{
constexpr double kGravity = 9.80665;

template <class Range>
bool finiteRange(const Range& values)
{
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      return false;
    }
  }
  return true;
}

class Observer
{
public:
  explicit Observer(ros::NodeHandle& nh)
  {
    filtered_ = nh.subscribe("odometry/filtered", 5000, &Observer::odometry, this);
    wave_ = nh.subscribe("odometry/wave", 5000, &Observer::odometry, this);
    bias_ = nh.subscribe("bias_state", 5000, &Observer::bias, this);
    diagnostics_ = nh.subscribe("/diagnostics", 100, &Observer::diagnostics, this);
    tf_ = nh.subscribe("/tf", 5000, &Observer::tf, this);
    path_filtered_ = nh.subscribe("path/filtered", 100, &Observer::path, this);
    path_raw_ = nh.subscribe("path/raw", 100, &Observer::path, this);
  }

  void tf(const tf2_msgs::TFMessage::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& t : msg->transforms)
    {
      if (t.header.frame_id == "odom" && t.child_frame_id == "base_link")
      {
        ++tf_count_;
        const auto& r = t.transform.rotation;
        const std::array<double, 7> v = {
          t.transform.translation.x, t.transform.translation.y, t.transform.translation.z, r.w, r.x, r.y, r.z
        };
        if (!finiteRange(v))
        {
          ++nonfinite_;
        }
      }
    }
  }

  void path(const nav_msgs::Path::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++path_count_;
    max_path_length_ = std::max(max_path_length_, msg->poses.size());
    for (const auto& pose : msg->poses)
    {
      const auto& p = pose.pose.position;
      const std::array<double, 3> v = { p.x, p.y, p.z };
      if (!finiteRange(v))
      {
        ++nonfinite_;
      }
    }
  }

  std::size_t tfCount()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return tf_count_;
  }
  std::size_t pathCount()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return path_count_;
  }
  std::size_t maxPathLength()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return max_path_length_;
  }

  void odometry(const nav_msgs::Odometry::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& p = msg->pose.pose;
    const std::array<double, 7> pose = { p.position.x,    p.position.y,    p.position.z,   p.orientation.w,
                                         p.orientation.x, p.orientation.y, p.orientation.z };
    const auto& t = msg->twist.twist;
    const std::array<double, 6> twist = { t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z };
    if (!finiteRange(pose) || !finiteRange(twist) || !finiteRange(msg->pose.covariance) ||
        !finiteRange(msg->twist.covariance))
    {
      ++nonfinite_;
    }
    for (int i = 0; i < 6; ++i)
    {
      if (msg->pose.covariance[i * 7] < 0.0)
      {
        ++negative_variance_;
      }
    }
    ++odometry_count_;
    last_stamp_ = std::max(last_stamp_, msg->header.stamp.toSec());
  }

  void bias(const periodic_bias_compensation::BiasState::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!finiteRange(msg->constant_bias) || !finiteRange(msg->periodic_bias) || !finiteRange(msg->dominant_frequency) ||
        !finiteRange(msg->period_samples) || !finiteRange(msg->d_v) || !finiteRange(msg->d_p))
    {
      ++nonfinite_;
    }
  }

  void diagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : msg->status)
    {
      if (status.name.find("bias compensation") == std::string::npos)
      {
        continue;
      }
      std::map<std::string, std::string> values;
      for (const auto& kv : status.values)
      {
        values[kv.key] = kv.value;
      }
      diagnostic_values_ = values;
      levels_seen_[status.level] = status.message;
    }
  }

  std::size_t nonfinite()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return nonfinite_;
  }
  std::size_t negativeVariance()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return negative_variance_;
  }
  double lastStamp()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_stamp_;
  }
  std::map<std::string, std::string> values()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return diagnostic_values_;
  }
  std::map<int, std::string> levels()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return levels_seen_;
  }
  /// Diagnostic value as a number, -1 when absent.
  long value(const std::string& key)
  {
    const auto v = values();
    const auto it = v.find(key);
    return it == v.end() ? -1 : std::stol(it->second);
  }

private:
  std::mutex mutex_;
  std::size_t tf_count_ = 0;
  std::size_t path_count_ = 0;
  std::size_t max_path_length_ = 0;
  std::size_t nonfinite_ = 0;
  std::size_t negative_variance_ = 0;
  std::size_t odometry_count_ = 0;
  double last_stamp_ = 0.0;
  std::map<std::string, std::string> diagnostic_values_;
  std::map<int, std::string> levels_seen_;
  // Declared last: destroyed first, so no callback in flight outlives the state it writes.
  ros::Subscriber filtered_, wave_, bias_, diagnostics_, tf_, path_filtered_, path_raw_;
};

/// Publishes crafted IMU messages and keeps the stamp and the sent count.
class ImuSource
{
public:
  explicit ImuSource(ros::NodeHandle& nh) : pub_(nh.advertise<sensor_msgs::Imu>("imu/data", 5000))
  {
  }

  bool waitForSubscriber(double timeout)
  {
    const ros::WallTime start = ros::WallTime::now();
    while (pub_.getNumSubscribers() == 0 && (ros::WallTime::now() - start).toSec() < timeout)
    {
      ros::WallDuration(0.05).sleep();
    }
    ros::WallDuration(0.5).sleep();
    return pub_.getNumSubscribers() > 0;
  }

  /// A valid sample at time t [s]: still, level, small surge oscillation.
  sensor_msgs::Imu good(double t) const
  {
    sensor_msgs::Imu msg;
    msg.header.stamp = ros::Time(t);
    msg.header.frame_id = "imu_link";
    msg.linear_acceleration.x = 0.05 * std::sin(2.0 * M_PI * 0.5 * t);
    msg.linear_acceleration.z = kGravity;
    msg.orientation.w = 1.0;
    for (int i = 0; i < 3; ++i)
    {
      msg.orientation_covariance[4 * i] = 1e-4;
      msg.angular_velocity_covariance[4 * i] = 1e-6;
      msg.linear_acceleration_covariance[4 * i] = 1e-4;
    }
    return msg;
  }

  void send(const sensor_msgs::Imu& msg)
  {
    pub_.publish(msg);
    ++sent_;
    // Faster than real time but slow enough for the subscriber queue.
    ros::WallDuration(0.002).sleep();
  }

  /// n valid samples every dt [s] from the current time.
  void run(int n, double dt, bool with_orientation = true)
  {
    for (int i = 0; i < n; ++i)
    {
      t_ += dt;
      sensor_msgs::Imu msg = good(t_);
      if (!with_orientation)
      {
        msg.orientation_covariance[0] = -1.0;
        msg.orientation.w = 0.0;
      }
      send(msg);
    }
  }

  double t_ = 0.0;
  std::size_t sent_ = 0;

private:
  ros::Publisher pub_;
};
}  // namespace

TEST(BadInput, EveryCaseCountedNothingNonFinitePublished)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  Observer observer(nh);
  ImuSource source(nh);
  ASSERT_TRUE(source.waitForSubscriber(30.0)) << "the compensator did not subscribe to imu/data";

  const double dt = 0.01;
  source.t_ = std::floor(ros::WallTime::now().toSec());
  // Valid data first: mounting lookup times out (no tf here) after mount_timeout, then output.
  source.run(300, dt);

  // NaN / Inf in each used field.
  sensor_msgs::Imu m = source.good(source.t_ += dt);
  m.linear_acceleration.x = std::nan("");
  source.send(m);
  m = source.good(source.t_ += dt);
  m.angular_velocity.z = std::numeric_limits<double>::infinity();
  source.send(m);
  m = source.good(source.t_ += dt);
  m.orientation.x = std::nan("");
  source.send(m);
  source.run(20, dt);

  // Non-unit quaternions (all zeros means "no orientation": input_sanity.test).
  m = source.good(source.t_ += dt);
  m.orientation.w = 0.5;
  source.send(m);
  m = source.good(source.t_ += dt);
  m.orientation.w = 1.5;
  source.send(m);
  source.run(20, dt);

  // Wrong frame_id.
  for (int i = 0; i < 2; ++i)
  {
    m = source.good(source.t_ += dt);
    m.header.frame_id = "other_frame";
    source.send(m);
  }
  source.run(20, dt);

  // Duplicated stamp.
  source.send(source.good(source.t_));
  source.run(20, dt);

  // Lone stamp glitches of real drivers: one stamp 5 s in the past, one stamped 0, one 1 ms after
  // its predecessor. Each is dropped and counted; none is a restart.
  source.send(source.good(source.t_ - 5.0));
  source.run(20, dt);
  source.send(source.good(0.0));
  source.run(20, dt);
  source.send(source.good(source.t_ + 0.001));
  source.run(20, dt);

  // Stamps going backwards (a bag replayed again): clean reset, then forward again.
  source.t_ -= 3.0;
  source.run(150, dt);

  // A gap longer than max_gap.
  source.t_ += 2.0;
  source.run(150, dt);

  // The sample rate halves.
  source.run(200, 2.0 * dt);

  // No orientation in the message (orientation_covariance[0] = -1).
  source.run(200, 2.0 * dt, false);

  // Valid data again: the output must follow.
  const double final_start = source.t_;
  source.run(200, 2.0 * dt);

  // Wait until diagnostics have seen every message.
  const ros::WallTime start = ros::WallTime::now();
  while (observer.value("received") < static_cast<long>(source.sent_) && (ros::WallTime::now() - start).toSec() < 20.0)
  {
    ros::WallDuration(0.2).sleep();
  }
  ros::WallDuration(0.5).sleep();

  EXPECT_EQ(observer.nonfinite(), 0u) << "a NaN/Inf was published";
  EXPECT_EQ(observer.negativeVariance(), 0u) << "a pose variance was negative (-1 is not allowed)";
  EXPECT_GT(observer.lastStamp(), final_start) << "no output for the valid data after the bad input";
  EXPECT_NEAR(observer.lastStamp(), source.t_, 1e-6) << "the last valid sample gave no output";

  EXPECT_EQ(observer.value("received"), static_cast<long>(source.sent_));
  EXPECT_EQ(observer.value("rejected non-finite"), 3);
  EXPECT_EQ(observer.value("rejected bad quaternion"), 2);
  EXPECT_EQ(observer.value("rejected wrong frame"), 2);
  EXPECT_EQ(observer.value("rejected duplicate stamp"), 1);
  EXPECT_EQ(observer.value("dropped stamp glitches"), 3);
  EXPECT_EQ(observer.value("backwards resets"), 1);
  EXPECT_EQ(observer.value("gap resets"), 1);
  EXPECT_GE(observer.value("sample rate changes"), 1);
  EXPECT_EQ(observer.value("non-finite outputs suppressed"), 0);
  EXPECT_GT(observer.value("dropped waiting for mounting"), 0);
  EXPECT_EQ(observer.values()["mounting"], "identity (tf lookup failed)");
  EXPECT_EQ(observer.values()["input frame"], "imu_link");

  // publish_tf, path/filtered and path/raw (bounded by path_max_length) are set in the .test.
  EXPECT_GT(observer.tfCount(), 0u) << "no odom -> base_link on /tf";
  EXPECT_GT(observer.pathCount(), 0u) << "no path/filtered or path/raw";
  EXPECT_LE(observer.maxPathLength(), static_cast<std::size_t>(pnh.param("path_max_length", 5)));

  // The bad input was reported at WARN level with a readable message at least once.
  const auto levels = observer.levels();
  EXPECT_TRUE(levels.count(diagnostic_msgs::DiagnosticStatus::WARN) > 0) << "no WARN status seen";

  // Input stops: the status turns to ERROR with a message saying so.
  const ros::WallTime silent = ros::WallTime::now();
  bool error_seen = false;
  while (!error_seen && (ros::WallTime::now() - silent).toSec() < 10.0)
  {
    const auto seen = observer.levels();
    const auto it = seen.find(diagnostic_msgs::DiagnosticStatus::ERROR);
    error_seen = it != seen.end() && it->second.find("no IMU data") != std::string::npos;
    ros::WallDuration(0.2).sleep();
  }
  EXPECT_TRUE(error_seen) << "no ERROR 'no IMU data' after the input stopped";

  // launch/record.launch runs alongside and must be writing its bag.
  const std::string record_path = pnh.param<std::string>("record_path", "");
  if (!record_path.empty())
  {
    EXPECT_TRUE(std::ifstream(record_path + ".active").good() || std::ifstream(record_path).good())
        << "record.launch is not writing " << record_path;
  }
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bad_input");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
