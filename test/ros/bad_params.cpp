// Invalid start-up parameters stop the compensator with nothing subscribed: the node
// (/node/compensator, unstable gain) and the nodelet (/nodelet/compensator, misspelt key) must
// exit (the FATAL message naming the key is checked on the same code path by
// test_compensate_bag; here the processes are gone before /rosout could relay it) and never
// subscribe to imu/data.
#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>

namespace
{
bool nodeAlive(const std::string& name)
{
  std::vector<std::string> nodes;
  ros::master::getNodes(nodes);
  return std::find(nodes.begin(), nodes.end(), name) != nodes.end();
}
}  // namespace

TEST(BadParameters, NodeAndNodeletRefuseToStart)
{
  ros::NodeHandle nh;
  ros::Publisher node_imu = nh.advertise<sensor_msgs::Imu>("node/imu/data", 1);
  ros::Publisher nodelet_imu = nh.advertise<sensor_msgs::Imu>("nodelet/imu/data", 1);

  // Both start with the test; give them time to read their parameters and stop.
  const ros::WallTime start = ros::WallTime::now();
  std::size_t subscribed = 0;
  while ((ros::WallTime::now() - start).toSec() < 8.0)
  {
    subscribed += node_imu.getNumSubscribers() + nodelet_imu.getNumSubscribers();
    ros::WallDuration(0.1).sleep();
  }
  EXPECT_EQ(subscribed, 0u) << "a compensator subscribed to imu/data despite invalid parameters";
  EXPECT_FALSE(nodeAlive("/node/compensator")) << "the node kept running with an unstable gain";
  EXPECT_FALSE(nodeAlive("/nodelet/compensator")) << "the nodelet kept running with an unknown key";
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bad_params_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
