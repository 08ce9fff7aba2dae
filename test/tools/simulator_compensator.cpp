// rostest: simulator_node (publish_clock, /use_sim_time) -> compensator (compensator.launch):
// odometry/filtered arrives, finite, stamped on the simulated clock.
#include <atomic>
#include <cmath>
#include <mutex>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

namespace
{
std::mutex g_mutex;
int g_count = 0;
int g_nonfinite = 0;
double g_last_stamp = 0.0;

void onOdometry(const nav_msgs::Odometry::ConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(g_mutex);
  ++g_count;
  const auto& p = msg->pose.pose.position;
  const auto& v = msg->twist.twist.linear;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(v.x) || !std::isfinite(v.y) ||
      !std::isfinite(v.z))
  {
    ++g_nonfinite;
  }
  g_last_stamp = msg->header.stamp.toSec();
}
}  // namespace

TEST(SimulatorCompensator, OdometryFilteredArrivesOnSimulatedTime)
{
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe("odometry/filtered", 100, onOdometry);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(90.0);
  while (ros::WallTime::now() < deadline)
  {
    ros::spinOnce();
    ros::WallDuration(0.05).sleep();
    std::lock_guard<std::mutex> lock(g_mutex);
    if (g_count >= 50)
    {
      break;
    }
  }
  std::lock_guard<std::mutex> lock(g_mutex);
  EXPECT_GE(g_count, 50) << "odometry/filtered messages received";
  EXPECT_EQ(g_nonfinite, 0);
  // paper_bench.yaml starts at 1000 s simulated time
  EXPECT_GE(g_last_stamp, 1000.0);
  EXPECT_LT(g_last_stamp, 1100.0);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_simulator_compensator");
  return RUN_ALL_TESTS();
}
