// Run-time parameters and services of the compensator (nodelet in an external manager, through
// launch/compensator.launch manager:=...):
//   - a gain and the mode set through dynamic_reconfigure take effect (echoed by the server and
//     on the parameter server; bias_state.mode follows), each change logged at INFO with its old
//     and new value (read back from /rosout)
//   - a gain beyond its range (alpha 1000) is clamped by dynamic_reconfigure to the advertised
//     maximum, the largest value validate() accepts, and that is what the node reports and runs
//   - a band that breaks min_frequency < max_frequency is refused as a whole, logged at WARN
//     naming the changed key and the rule: the previous values come back
//   - ~calibrate restarts the constant-bias window; ~save_calibration writes calibration_file
//   - the IMU mounting comes from tf2: imu_link is published turned +90 deg about z on base_link,
//     so a level IMU gives a base orientation of -90 deg about z in odometry/filtered
// Private parameter: calibration_file, the path the compensator was given.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <dynamic_reconfigure/client.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/master.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "periodic_bias_compensation/BiasState.h"
#include "periodic_bias_compensation/CompensatorConfig.h"

namespace
{
using Tuning = periodic_bias_compensation_cfg::CompensatorConfig;

/// Publishes a level IMU at 100 Hz (stamps on wall time) in the background.
class ImuFeeder
{
public:
  explicit ImuFeeder(ros::NodeHandle& nh) : pub_(nh.advertise<sensor_msgs::Imu>("imu/data", 100))
  {
    thread_ = std::thread([this] {
      ros::WallRate rate(100.0);
      double t = std::floor(ros::WallTime::now().toSec());
      while (running_ && ros::ok())
      {
        t += 0.01;
        sensor_msgs::Imu msg;
        msg.header.stamp = ros::Time(t);
        msg.header.frame_id = "imu_link";
        msg.linear_acceleration.x = 0.3 * std::sin(2.0 * M_PI * 0.4 * t);
        msg.linear_acceleration.z = 9.80665;
        msg.orientation.w = 1.0;
        msg.orientation_covariance[0] = msg.orientation_covariance[4] = msg.orientation_covariance[8] = 1e-4;
        pub_.publish(msg);
        rate.sleep();
      }
    });
  }
  ~ImuFeeder()
  {
    running_ = false;
    thread_.join();
  }

private:
  ros::Publisher pub_;
  std::atomic<bool> running_{ true };
  std::thread thread_;
};

class BiasWatcher
{
public:
  explicit BiasWatcher(ros::NodeHandle& nh) : sub_(nh.subscribe("bias_state", 10, &BiasWatcher::callback, this))
  {
  }
  void callback(const periodic_bias_compensation::BiasState::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_ = *msg;
    ++count_;
  }
  /// Waits until the latest BiasState satisfies pred (wall time) [s].
  template <class Pred>
  bool waitFor(Pred pred, double timeout)
  {
    const ros::WallTime start = ros::WallTime::now();
    while ((ros::WallTime::now() - start).toSec() < timeout)
    {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (count_ > 0 && pred(last_))
        {
          return true;
        }
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }
  std::size_t count()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return count_;
  }

private:
  std::mutex mutex_;
  periodic_bias_compensation::BiasState last_;
  std::size_t count_ = 0;
  // Declared last: destroyed first, so no callback in flight outlives the state it writes.
  ros::Subscriber sub_;
};
/// The nodes the master lists as publishers (kind 0) or subscribers (kind 1) of `topic`; nothing
/// if it cannot be asked.
std::optional<std::vector<std::string>> nodesOn(const std::string& topic, int kind)
{
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", args, result, payload, true))
  {
    return std::nullopt;
  }
  std::vector<std::string> nodes;
  for (int i = 0; i < payload[kind].size(); ++i)
  {
    if (static_cast<std::string>(payload[kind][i][0]) == topic)
    {
      for (int j = 0; j < payload[kind][i][1].size(); ++j)
        nodes.push_back(static_cast<std::string>(payload[kind][i][1][j]));
    }
  }
  return nodes;
}

/// Publishers of /rosout known to the master (every node has one), -1 if it cannot be asked.
int rosoutPublishers()
{
  const auto nodes = nodesOn("/rosout", 0);
  return nodes ? static_cast<int>(nodes->size()) : -1;
}

/// Collects what the nodes log on /rosout (rostest starts no rosout node to aggregate it).
class LogWatcher
{
public:
  explicit LogWatcher(ros::NodeHandle& nh) : sub_(nh.subscribe("/rosout", 1000, &LogWatcher::callback, this))
  {
  }
  void callback(const rosgraph_msgs::Log::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    logs_.push_back(*msg);
  }
  /// Waits until connected to every node's /rosout (wall time) [s].
  bool connected(double timeout)
  {
    const ros::WallTime start = ros::WallTime::now();
    while ((ros::WallTime::now() - start).toSec() < timeout)
    {
      const int publishers = rosoutPublishers();
      if (publishers > 0 && static_cast<int>(sub_.getNumPublishers()) >= publishers)
      {
        return true;
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }
  /// Waits for a message at `level` that contains `text` (wall time) [s].
  bool waitFor(std::uint8_t level, const std::string& text, double timeout)
  {
    const ros::WallTime start = ros::WallTime::now();
    while ((ros::WallTime::now() - start).toSec() < timeout)
    {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& log : logs_)
        {
          if (log.level == level && log.msg.find(text) != std::string::npos)
          {
            return true;
          }
        }
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }
  std::string dump()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string text;
    for (const auto& log : logs_)
    {
      text += "  [" + std::to_string(log.level) + "] " + log.msg + "\n";
    }
    return text;
  }

private:
  std::mutex mutex_;
  std::vector<rosgraph_msgs::Log> logs_;
  // Declared last: destroyed first, so no callback in flight outlives the state it writes.
  ros::Subscriber sub_;
};
}  // namespace

class Reconfigure : public testing::Test
{
protected:
  Reconfigure() : feeder_(nh_), watcher_(nh_), logs_(nh_), client_("compensator")
  {
  }

  ros::NodeHandle nh_;
  ImuFeeder feeder_;
  BiasWatcher watcher_;
  LogWatcher logs_;
  dynamic_reconfigure::Client<Tuning> client_;
};

TEST_F(Reconfigure, ChangesAreLoggedClampedOrRefused)
{
  using rosgraph_msgs::Log;
  Tuning config;
  ASSERT_TRUE(client_.getCurrentConfiguration(config, ros::Duration(20.0))) << "no reconfigure server";
  EXPECT_DOUBLE_EQ(config.alpha_v_x, 0.5);
  EXPECT_EQ(config.mode, "default");
  ASSERT_TRUE(watcher_.waitFor([](const auto& b) { return b.mode == "default"; }, 20.0)) << "no bias_state";
  ASSERT_TRUE(logs_.connected(10.0)) << "not connected to every /rosout";

  // Valid change: echoed by the server, on the parameter server, in the behaviour and the log.
  config.alpha_v_x = 0.3;
  config.mode = "paper";
  ASSERT_TRUE(client_.setConfiguration(config));
  EXPECT_DOUBLE_EQ(config.alpha_v_x, 0.3);
  EXPECT_EQ(config.mode, "paper");
  double echoed = 0.0;
  ASSERT_TRUE(nh_.getParam("compensator/alpha_v_x", echoed));
  EXPECT_DOUBLE_EQ(echoed, 0.3);
  EXPECT_TRUE(watcher_.waitFor([](const auto& b) { return b.mode == "paper"; }, 5.0))
      << "bias_state does not show the new mode";
  EXPECT_TRUE(logs_.waitFor(Log::INFO, "reconfigure: alpha_v_x 0.5 -> 0.3", 5.0)) << logs_.dump();
  EXPECT_TRUE(logs_.waitFor(Log::INFO, "reconfigure: mode default -> paper", 5.0)) << logs_.dump();

  // Beyond the range (the comb loop diverges for alpha >= 2): dynamic_reconfigure clamps it to
  // the advertised maximum, which is the largest value the core accepts, so it runs as shown.
  const double alpha_max = Tuning::__getMax__().alpha_v_x;
  EXPECT_LT(alpha_max, 2.0);
  EXPECT_GT(alpha_max, 1.99);
  Tuning wild = config;
  wild.alpha_v_x = 1000.0;
  ASSERT_TRUE(client_.setConfiguration(wild));
  EXPECT_EQ(wild.alpha_v_x, alpha_max) << "the server reports another value than the clamped one";
  ASSERT_TRUE(nh_.getParam("compensator/alpha_v_x", echoed));
  EXPECT_EQ(echoed, alpha_max);
  Tuning current;
  ASSERT_TRUE(client_.getCurrentConfiguration(current, ros::Duration(5.0)));
  EXPECT_EQ(current.alpha_v_x, alpha_max);
  EXPECT_TRUE(logs_.waitFor(Log::INFO, "reconfigure: alpha_v_x 0.3 -> 1.9999999999999998", 5.0)) << logs_.dump();
  ASSERT_TRUE(client_.setConfiguration(config));
  EXPECT_DOUBLE_EQ(config.alpha_v_x, 0.3);

  // A band whose lower edge passes the upper one: refused as a whole, the previous values back,
  // and the warning names the key that was changed.
  Tuning bad = config;
  bad.min_frequency = 5.0;
  bad.alpha_p_z = 0.2;
  ASSERT_TRUE(client_.setConfiguration(bad));
  EXPECT_DOUBLE_EQ(bad.min_frequency, config.min_frequency) << "the refused value was not reverted in the response";
  EXPECT_DOUBLE_EQ(bad.alpha_p_z, config.alpha_p_z) << "part of a refused request was applied";
  ASSERT_TRUE(nh_.getParam("compensator/min_frequency", echoed));
  EXPECT_DOUBLE_EQ(echoed, config.min_frequency) << "the refused value reached the parameter server";
  EXPECT_TRUE(logs_.waitFor(Log::WARN,
                            "reconfigure of alpha_p_z, min_frequency refused, keeping the previous parameters: "
                            "min_frequency = 5 must be below max_frequency = 2",
                            5.0))
      << logs_.dump();
  bad = config;
  bad.max_frequency = 0.01;
  ASSERT_TRUE(client_.setConfiguration(bad));
  EXPECT_DOUBLE_EQ(bad.max_frequency, config.max_frequency);
  EXPECT_TRUE(logs_.waitFor(Log::WARN, "max_frequency = 0.01 must be above min_frequency = 0.05", 5.0)) << logs_.dump();

  ASSERT_TRUE(client_.getCurrentConfiguration(current, ros::Duration(5.0)));
  EXPECT_DOUBLE_EQ(current.alpha_v_x, 0.3);
  EXPECT_DOUBLE_EQ(current.min_frequency, config.min_frequency);
  EXPECT_EQ(current.mode, "paper");

  // Still running with the last good configuration.
  const std::size_t before = watcher_.count();
  EXPECT_TRUE(watcher_.waitFor([](const auto& b) { return b.mode == "paper"; }, 5.0));
  ros::WallDuration(0.5).sleep();
  EXPECT_GT(watcher_.count(), before) << "bias_state stopped after a refused reconfigure";
}

TEST_F(Reconfigure, CalibrateAndSaveServices)
{
  ASSERT_TRUE(ros::service::waitForService("compensator/calibrate", 20000));
  ASSERT_TRUE(watcher_.waitFor([](const auto& b) { return b.calibrated; }, 20.0)) << "never calibrated";

  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::call("compensator/calibrate", trigger));
  EXPECT_TRUE(trigger.response.success);
  EXPECT_NE(trigger.response.message.find("calibration"), std::string::npos) << trigger.response.message;
  EXPECT_TRUE(watcher_.waitFor([](const auto& b) { return !b.calibrated; }, 5.0)) << "calibration did not restart";
  EXPECT_TRUE(watcher_.waitFor([](const auto& b) { return b.calibrated; }, 20.0)) << "calibration did not finish";

  const std::string file = ros::NodeHandle("~").param<std::string>("calibration_file", "");
  ASSERT_FALSE(file.empty());
  std::remove(file.c_str());
  ASSERT_TRUE(ros::service::call("compensator/save_calibration", trigger));
  EXPECT_TRUE(trigger.response.success) << trigger.response.message;
  std::ifstream written(file);
  ASSERT_TRUE(written.good()) << file << " not written";
  const std::string content((std::istreambuf_iterator<char>(written)), std::istreambuf_iterator<char>());
  EXPECT_NE(content.find("constant_bias"), std::string::npos) << content;
}

TEST_F(Reconfigure, MountingFromTf)
{
  std::mutex mutex;
  nav_msgs::Odometry last;
  bool received = false;
  ros::Subscriber sub =
      nh_.subscribe<nav_msgs::Odometry>("odometry/filtered", 10, [&](const nav_msgs::Odometry::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(mutex);
        last = *msg;
        received = true;
      });
  const ros::WallTime start = ros::WallTime::now();
  while ((ros::WallTime::now() - start).toSec() < 10.0)
  {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (received)
      {
        break;
      }
    }
    ros::WallDuration(0.05).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_TRUE(received) << "no odometry/filtered";
  const auto& q = last.pose.pose.orientation;
  EXPECT_NEAR(std::abs(q.w), std::cos(M_PI / 4.0), 1e-3);
  EXPECT_NEAR(q.z * (q.w < 0 ? -1.0 : 1.0), -std::sin(M_PI / 4.0), 1e-3) << "mounting rotation not applied";
  EXPECT_EQ(last.child_frame_id, "base_link");

  // The mounting is decided: the nodelet's manager no longer listens to /tf (where the nodelet
  // publishes one transform per sample).
  std::optional<std::vector<std::string>> tf_subscribers;
  for (const ros::WallTime asked = ros::WallTime::now(); (ros::WallTime::now() - asked).toSec() < 5.0;
       ros::WallDuration(0.1).sleep())
  {
    tf_subscribers = nodesOn("/tf", 1);
    if (tf_subscribers && std::count(tf_subscribers->begin(), tf_subscribers->end(), "/manager") == 0)
      break;
  }
  ASSERT_TRUE(tf_subscribers.has_value()) << "the master could not be asked";
  EXPECT_EQ(std::count(tf_subscribers->begin(), tf_subscribers->end(), "/manager"), 0);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "reconfigure_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  // IMU mounted turned +90 deg about z: published before any IMU data (latched /tf_static).
  tf2_ros::StaticTransformBroadcaster static_tf;
  geometry_msgs::TransformStamped mount;
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "imu_link";
  mount.transform.rotation.z = std::sin(M_PI / 4.0);
  mount.transform.rotation.w = std::cos(M_PI / 4.0);
  static_tf.sendTransform(mount);
  return RUN_ALL_TESTS();
}
