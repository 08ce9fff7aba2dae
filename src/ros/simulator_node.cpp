// simulator_node: publishes a simulator scenario live, paced against the wall clock, with the
// scenario's sample times as header stamps (and as /clock when ~publish_clock is true).
//
// Private parameters:
//   ~scenario       path of the scenario YAML (required)
//   ~seed           random seed [-] (default: the scenario's seed)
//   ~rate_factor    simulated seconds per wall second [-] (1.0 = real time, 0 = as fast as possible)
//   ~publish_clock  publish rosgraph_msgs/Clock on /clock (for /use_sim_time) [bool], default false
// Topics: imu/data, imu/temperature (with a temperature profile), ground_truth/odometry,
// ground_truth/slow, ground_truth/wave, /clock. Frames as simulate_imu (docs/simulator.md).
#include <string>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/Temperature.h>

#include "periodic_bias_compensation/sim/simulator.h"

namespace sim = periodic_bias_compensation::sim;

namespace
{
geometry_msgs::Vector3 toVector(const sim::Vector3& v)
{
  geometry_msgs::Vector3 m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}

geometry_msgs::Quaternion toQuaternion(const sim::Quaternion& q)
{
  geometry_msgs::Quaternion m;
  m.w = q.w();
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  return m;
}

nav_msgs::Odometry toOdometry(const ros::Time& stamp, const sim::OdometryState& state)
{
  nav_msgs::Odometry m;
  m.header.stamp = stamp;
  m.header.frame_id = "odom";
  m.child_frame_id = "base_link";
  m.pose.pose.position.x = state.position.x();
  m.pose.pose.position.y = state.position.y();
  m.pose.pose.position.z = state.position.z();
  m.pose.pose.orientation = toQuaternion(state.orientation);
  m.twist.twist.linear = toVector(state.linear_velocity);
  m.twist.twist.angular = toVector(state.angular_velocity);
  return m;
}
}  // namespace

int main(int argc, char** argv)
{
  ros::init(argc, argv, "simulator_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");

  std::string path;
  if (!pnh.getParam("scenario", path))
  {
    ROS_FATAL("simulator_node: private parameter ~scenario (path of a scenario YAML) is required");
    return 1;
  }
  double rate_factor = 1.0;
  bool publish_clock = false;
  pnh.param("rate_factor", rate_factor, 1.0);
  pnh.param("publish_clock", publish_clock, false);
  if (rate_factor < 0.0)
  {
    ROS_FATAL("simulator_node: ~rate_factor must be >= 0 (got %g)", rate_factor);
    return 1;
  }

  sim::Scenario scenario;
  try
  {
    scenario = sim::loadScenario(path);
  }
  catch (const std::exception& e)
  {
    ROS_FATAL("simulator_node: %s", e.what());
    return 1;
  }
  int seed = static_cast<int>(scenario.seed);
  pnh.param("seed", seed, seed);
  sim::Simulator simulator(scenario, static_cast<std::uint64_t>(seed));
  const sim::ImuCovariance cov = sim::imuCovariance(simulator.scenario());

  ros::Publisher imu_pub = nh.advertise<sensor_msgs::Imu>("imu/data", 200);
  ros::Publisher temperature_pub = nh.advertise<sensor_msgs::Temperature>("imu/temperature", 50);
  ros::Publisher odom_pub = nh.advertise<nav_msgs::Odometry>("ground_truth/odometry", 200);
  ros::Publisher slow_pub = nh.advertise<nav_msgs::Odometry>("ground_truth/slow", 200);
  ros::Publisher wave_pub = nh.advertise<nav_msgs::Odometry>("ground_truth/wave", 200);
  ros::Publisher clock_pub;
  if (publish_clock)
  {
    clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  }
  ROS_INFO("simulator_node: %s, seed %d, %lld samples at %g Hz, rate factor %g%s", path.c_str(), seed,
           static_cast<long long>(simulator.sampleCount()), scenario.rate, rate_factor,
           publish_clock ? ", publishing /clock" : "");

  sensor_msgs::Imu imu;
  imu.header.frame_id = "imu_link";
  for (int i = 0; i < 3; ++i)
  {
    imu.orientation_covariance[4 * i] = cov.orientation_variance;
    imu.angular_velocity_covariance[4 * i] = cov.gyro_variance[i];
    imu.linear_acceleration_covariance[4 * i] = cov.accel_variance[i];
  }
  sensor_msgs::Temperature temperature;
  temperature.header.frame_id = "imu_link";

  const ros::WallTime wall_start = ros::WallTime::now();
  sim::Sample s;
  while (ros::ok() && simulator.next(&s))
  {
    if (rate_factor > 0.0)
    {
      const ros::WallTime due = wall_start + ros::WallDuration(s.elapsed / rate_factor);
      const ros::WallDuration wait = due - ros::WallTime::now();
      if (wait > ros::WallDuration(0.0))
      {
        wait.sleep();
      }
    }
    const ros::Time t(s.t);
    if (publish_clock)
    {
      rosgraph_msgs::Clock clock;
      clock.clock = t;
      clock_pub.publish(clock);
    }
    if (!s.dropped)
    {
      imu.header.stamp = ros::Time(s.stamp);
      imu.header.seq = static_cast<std::uint32_t>(s.index);
      imu.orientation = toQuaternion(s.orientation);
      imu.angular_velocity = toVector(s.gyro);
      imu.linear_acceleration = toVector(s.accel);
      imu_pub.publish(imu);
      if (s.has_temperature)
      {
        temperature.header.stamp = imu.header.stamp;
        temperature.temperature = s.temperature;
        temperature_pub.publish(temperature);
      }
    }
    const sim::TruthOdometry odom = sim::truthOdometry(s.truth);
    odom_pub.publish(toOdometry(t, odom.total));
    slow_pub.publish(toOdometry(t, odom.slow));
    wave_pub.publish(toOdometry(t, odom.wave));
    ros::spinOnce();
  }
  ROS_INFO("simulator_node: scenario finished");
  return 0;
}
