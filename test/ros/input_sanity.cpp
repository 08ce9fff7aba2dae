// Input as real drivers send it, through the real topic, one compensator per case (namespaces
// set up by input_sanity.test): accelerations in g, all-zero orientation quaternions without
// the covariance -1 flag, an empty frame_id on the first message, input that is all refused, and
// clean input with identity mounting declared. Asserts what /diagnostics says of each (level and
// message) and whether odometry comes out.
#include <cmath>
#include <map>
#include <mutex>
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>

#include "periodic_bias_compensation/BiasState.h"

namespace
{
constexpr double kGravity = 9.80665;
constexpr double kRate = 50.0;

/// Latest /diagnostics status of each compensator (by the namespace in its name), and the
/// odometry and bias states each namespace published.
class Watcher
{
public:
  explicit Watcher(ros::NodeHandle& nh) : nh_(nh)
  {
    diagnostics_ = nh.subscribe("/diagnostics", 100, &Watcher::diagnostics, this);
  }

  void watch(const std::string& ns)
  {
    subscribers_.push_back(nh_.subscribe<nav_msgs::Odometry>("/" + ns + "/odometry/filtered", 1000,
                                                             [this, ns](const nav_msgs::Odometry::ConstPtr&) {
                                                               std::lock_guard<std::mutex> lock(mutex_);
                                                               ++odometry_[ns];
                                                             }));
    subscribers_.push_back(nh_.subscribe<periodic_bias_compensation::BiasState>(
        "/" + ns + "/bias_state", 1000, [this, ns](const periodic_bias_compensation::BiasState::ConstPtr& msg) {
          std::lock_guard<std::mutex> lock(mutex_);
          last_state_[ns] = msg->state;
        }));
  }

  void diagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : msg->status)
    {
      if (status.name.find("bias compensation") == std::string::npos)
        continue;
      for (const char* ns : { "units", "zero_quaternion", "empty_frame", "refused", "normal" })
      {
        if (status.name.find(std::string("/") + ns + "/") != std::string::npos ||
            status.name.find(std::string(ns) + "/") == 0)
        {
          level_[ns] = status.level;
          message_[ns] = status.message;
          seen_[ns][status.level] = status.message;
          for (const auto& kv : status.values)
            values_[ns][kv.key] = kv.value;
        }
      }
    }
  }

  int level(const std::string& ns)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return level_.count(ns) ? level_[ns] : -1;
  }
  std::string message(const std::string& ns)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return message_[ns];
  }
  /// The latest message at `level`, empty if that level was never seen.
  std::string seen(const std::string& ns, int level)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_[ns].count(level) ? seen_[ns][level] : std::string();
  }
  std::string value(const std::string& ns, const std::string& key)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return values_[ns][key];
  }
  std::size_t odometry(const std::string& ns)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return odometry_[ns];
  }
  int state(const std::string& ns)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_state_.count(ns) ? last_state_[ns] : -1;
  }

private:
  ros::NodeHandle& nh_;
  std::mutex mutex_;
  std::map<std::string, int> level_;
  std::map<std::string, std::string> message_;
  std::map<std::string, std::map<int, std::string>> seen_;
  std::map<std::string, std::map<std::string, std::string>> values_;
  std::map<std::string, std::size_t> odometry_;
  std::map<std::string, int> last_state_;
  // Declared last: destroyed first, so no callback in flight outlives the state it writes.
  ros::Subscriber diagnostics_;
  std::vector<ros::Subscriber> subscribers_;
};

/// A level IMU at rest, shaken a little on x so that the estimator has something to follow.
sensor_msgs::Imu sample(double t, const std::string& frame)
{
  sensor_msgs::Imu m;
  m.header.stamp.fromSec(t);
  m.header.frame_id = frame;
  m.linear_acceleration.x = 0.2 * std::sin(2.0 * M_PI * 0.4 * t);
  m.linear_acceleration.z = kGravity;
  m.orientation.w = 1.0;
  m.orientation_covariance[0] = 1e-4;
  return m;
}

/// Publishes `seconds` of samples to every namespace at once, each message shaped by its case.
void publishAll(ros::NodeHandle& nh, double seconds)
{
  std::map<std::string, ros::Publisher> pubs;
  for (const char* ns : { "units", "zero_quaternion", "empty_frame", "refused", "normal" })
    pubs[ns] = nh.advertise<sensor_msgs::Imu>(std::string("/") + ns + "/imu/data", 1000);
  const ros::WallTime connect_deadline = ros::WallTime::now() + ros::WallDuration(20.0);
  for (auto& [ns, pub] : pubs)
    while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < connect_deadline)
      ros::WallDuration(0.05).sleep();

  const double t0 = 1.7e9;
  ros::WallRate rate(kRate);
  for (int k = 0; k < static_cast<int>(seconds * kRate) && ros::ok(); ++k)
  {
    const double t = t0 + k / kRate;
    sensor_msgs::Imu m = sample(t, "imu_link");

    sensor_msgs::Imu g = m;  // a driver publishing g (REP-145 asks for m/s^2)
    g.linear_acceleration.x /= kGravity;
    g.linear_acceleration.z /= kGravity;
    pubs["units"].publish(g);

    sensor_msgs::Imu zero = m;  // no AHRS: zeros, but no covariance -1 flag
    zero.orientation.w = 0.0;
    zero.orientation_covariance[0] = 0.0;
    pubs["zero_quaternion"].publish(zero);

    sensor_msgs::Imu first = m;  // the first message: empty frame_id and unusable
    if (k == 0)
    {
      first.header.frame_id = "";
      first.linear_acceleration.z = std::nan("");
    }
    pubs["empty_frame"].publish(first);

    sensor_msgs::Imu refused = m;  // every orientation non-unit: every sample refused
    refused.orientation.w = 1.5;
    pubs["refused"].publish(refused);

    pubs["normal"].publish(m);
    rate.sleep();
  }
}
}  // namespace

TEST(InputSanity, DiagnosticsSayWhatIsWrongWithTheInput)
{
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  Watcher watcher(nh);
  for (const char* ns : { "units", "zero_quaternion", "empty_frame", "refused", "normal" })
    watcher.watch(ns);

  // Before any input the diagnostics say so (not a levelling that has not happened).
  const ros::WallTime first_diagnostics = ros::WallTime::now() + ros::WallDuration(20.0);
  while (watcher.value("normal", "orientation").empty() && ros::WallTime::now() < first_diagnostics)
    ros::WallDuration(0.1).sleep();
  EXPECT_EQ(watcher.value("normal", "orientation"), "no input yet");

  // 5 s: each compensator calibrates (1 s window) and runs; diagnostics come every second.
  publishAll(nh, 5.0);
  ros::WallDuration(1.5).sleep();

  using diagnostic_msgs::DiagnosticStatus;
  const int error = DiagnosticStatus::ERROR;
  // Accelerations in g: ERROR, named.
  EXPECT_NE(watcher.seen("units", error).find("looks like g"), std::string::npos) << watcher.message("units");

  // All-zero quaternions: no orientation, used; never a refusal.
  EXPECT_GT(watcher.odometry("zero_quaternion"), 100u);
  EXPECT_EQ(watcher.seen("zero_quaternion", error), "");
  EXPECT_EQ(watcher.value("zero_quaternion", "rejected bad quaternion"), "0");
  EXPECT_NE(watcher.value("zero_quaternion", "accepted without orientation"), "0");
  EXPECT_EQ(watcher.value("zero_quaternion", "orientation").rfind("none in the input: levelled with the ", 0), 0u)
      << watcher.value("zero_quaternion", "orientation");

  // The empty, unusable first message does not fix the frame: the rest is used, and the frame
  // learnt is that of the first message used.
  EXPECT_GT(watcher.odometry("empty_frame"), 100u);
  EXPECT_EQ(watcher.value("empty_frame", "rejected wrong frame"), "0");
  EXPECT_EQ(watcher.value("empty_frame", "input frame"), "imu_link");

  // Everything refused while input arrives: ERROR, not a WARN that looks like running.
  EXPECT_EQ(watcher.odometry("refused"), 0u);
  EXPECT_NE(watcher.seen("refused", error).find("nothing was published"), std::string::npos)
      << watcher.message("refused");

  // Clean input, identity mounting declared, no transform published: OK once calibrated, and the
  // bias state says it is tracking.
  EXPECT_GT(watcher.odometry("normal"), 100u);
  EXPECT_EQ(watcher.level("normal"), DiagnosticStatus::OK) << watcher.message("normal");
  EXPECT_EQ(watcher.value("normal", "orientation"), "from the IMU message");
  EXPECT_EQ(watcher.state("normal"), periodic_bias_compensation::BiasState::STATE_TRACKING);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "input_sanity_test");
  return RUN_ALL_TESTS();
}
