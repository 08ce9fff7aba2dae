// Stand-alone node: creates the CompensatorRos wrapper and spins.
#include <exception>

#include <ros/ros.h>

#include "periodic_bias_compensation/ros/compensator_ros.h"

int main(int argc, char** argv)
{
  ros::init(argc, argv, "compensator");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  std::unique_ptr<periodic_bias_compensation::CompensatorRos> compensator;
  try
  {
    compensator = std::make_unique<periodic_bias_compensation::CompensatorRos>(nh, pnh);
  }
  catch (const std::exception& e)
  {
    ROS_FATAL("bias compensation not started: %s", e.what());
    return 1;
  }
  ros::spin();
  return 0;
}
