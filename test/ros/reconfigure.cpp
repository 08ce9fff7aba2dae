// Run-time parameters and services of the compensator (nodelet in an external manager, through
// launch/compensator.launch manager:=...):
//   - a gain and the mode set through dynamic_reconfigure take effect (echoed by the server and
//     on the parameter server; bias_state.mode follows)
//   - an unstable gain and an empty frequency band are refused: the previous values come back
//   - ~calibrate restarts the constant-bias window; ~save_calibration writes calibration_file
//   - the IMU mounting comes from tf2: imu_link is published turned +90 deg about z on base_link,
//     so a level IMU gives a base orientation of -90 deg about z in odometry/filtered
// Private parameter: calibration_file, the path the compensator was given.
#include <atomic>
#include <cmath>
#include <fstream>
#include <mutex>
#include <thread>

#include <dynamic_reconfigure/client.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Trigger.h>

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
  explicit BiasWatcher(ros::NodeHandle& nh)
    : sub_(nh.subscribe("bias_state", 10, &BiasWatcher::callback, this))
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
  ros::Subscriber sub_;
  std::mutex mutex_;
  periodic_bias_compensation::BiasState last_;
  std::size_t count_ = 0;
};
}  // namespace

class Reconfigure : public testing::Test
{
protected:
  Reconfigure() : feeder_(nh_), watcher_(nh_), client_("compensator") {}

  ros::NodeHandle nh_;
  ImuFeeder feeder_;
  BiasWatcher watcher_;
  dynamic_reconfigure::Client<Tuning> client_;
};

TEST_F(Reconfigure, GainTakesEffectAndUnstableValuesAreRefused)
{
  Tuning config;
  ASSERT_TRUE(client_.getCurrentConfiguration(config, ros::Duration(20.0))) << "no reconfigure server";
  EXPECT_DOUBLE_EQ(config.alpha_v_x, 0.5);
  EXPECT_EQ(config.mode, "default");
  ASSERT_TRUE(watcher_.waitFor([](const auto& b) { return b.mode == "default"; }, 20.0)) << "no bias_state";

  // Valid change: echoed by the server, on the parameter server, and in the behaviour.
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

  // Unstable gain (the comb loop diverges for alpha >= 2): refused, previous value back.
  Tuning bad = config;
  bad.alpha_v_x = 2.5;
  ASSERT_TRUE(client_.setConfiguration(bad));
  EXPECT_DOUBLE_EQ(bad.alpha_v_x, 0.3) << "the refused value was not reverted in the response";
  ASSERT_TRUE(nh_.getParam("compensator/alpha_v_x", echoed));
  EXPECT_DOUBLE_EQ(echoed, 0.3) << "the refused value reached the parameter server";

  // Out of range beta and an empty frequency band: refused as a whole.
  bad = config;
  bad.beta_v_y = 50.0;
  bad.alpha_p_z = 0.2;
  ASSERT_TRUE(client_.setConfiguration(bad));
  EXPECT_DOUBLE_EQ(bad.beta_v_y, config.beta_v_y);
  EXPECT_DOUBLE_EQ(bad.alpha_p_z, config.alpha_p_z) << "part of a refused request was applied";
  bad = config;
  bad.max_frequency = 0.01;
  ASSERT_TRUE(client_.setConfiguration(bad));
  EXPECT_DOUBLE_EQ(bad.max_frequency, config.max_frequency);

  Tuning current;
  ASSERT_TRUE(client_.getCurrentConfiguration(current, ros::Duration(5.0)));
  EXPECT_DOUBLE_EQ(current.alpha_v_x, 0.3);
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
  ros::Subscriber sub = nh_.subscribe<nav_msgs::Odometry>(
      "odometry/filtered", 10, [&](const nav_msgs::Odometry::ConstPtr& msg) {
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
