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

#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include "periodic_bias_compensation/ros/sim_messages.h"
#include "periodic_bias_compensation/sim/simulator.h"

namespace pbc = periodic_bias_compensation;
namespace sim = periodic_bias_compensation::sim;

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
  const pbc::SimMessageBuilder builder(simulator.scenario());

  using Topics = pbc::SimTopics;
  ros::Publisher imu_pub = nh.advertise<sensor_msgs::Imu>(Topics::kImu, 200);
  ros::Publisher temperature_pub = nh.advertise<sensor_msgs::Temperature>(Topics::kTemperature, 50);
  ros::Publisher odom_pub = nh.advertise<nav_msgs::Odometry>(Topics::kTruth, 200);
  ros::Publisher slow_pub = nh.advertise<nav_msgs::Odometry>(Topics::kTruthSlow, 200);
  ros::Publisher wave_pub = nh.advertise<nav_msgs::Odometry>(Topics::kTruthWave, 200);
  ros::Publisher clock_pub;
  if (publish_clock)
  {
    clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  }
  ROS_INFO("simulator_node: %s, seed %d, %lld samples at %g Hz, rate factor %g%s", path.c_str(), seed,
           static_cast<long long>(simulator.sampleCount()), scenario.rate, rate_factor,
           publish_clock ? ", publishing /clock" : "");

  const ros::WallTime wall_start = ros::WallTime::now();
  sim::Sample s;
  pbc::SimMessages messages;
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
    builder.build(s, &messages);
    if (messages.has_imu)
    {
      imu_pub.publish(messages.imu);
    }
    if (messages.has_temperature)
    {
      temperature_pub.publish(messages.temperature);
    }
    odom_pub.publish(messages.truth);
    slow_pub.publish(messages.truth_slow);
    wave_pub.publish(messages.truth_wave);
    ros::spinOnce();
  }
  ROS_INFO("simulator_node: scenario finished");
  return 0;
}
