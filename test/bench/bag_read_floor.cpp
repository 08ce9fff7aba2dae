// bag_read_floor: the floor of compensate_bag's speed, a loop that only reads a bag. By default it
// reads the IMU messages (rosbag::View on the topic, each instantiated as sensor_msgs::Imu, as
// compensate_bag does) and sums one field so the work cannot be dropped; with --whole-bag it also
// reads every other message's bytes, as compensate_bag must (it copies ground_truth/* through).
// Run by scripts/bench.py, not a test.
//
//   bag_read_floor --in IN.bag [--imu-topic imu/data] [--whole-bag]
//
// Output: one line "messages=N wall_s=S messages_per_s=R read=M checksum=C" (N IMU messages, M
// messages read in all).
#include <chrono>
#include <cstdint>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>

#include "periodic_bias_compensation/tools/command_line.h"

namespace pbc = periodic_bias_compensation;

int main(int argc, char** argv)
{
  std::string in;
  std::string topic = "imu/data";
  bool whole_bag = false;
  pbc::CommandLine cli("usage: bag_read_floor --in IN.bag [--imu-topic imu/data] [--whole-bag]\n");
  cli.text("--in", &in).text("--imu-topic", &topic).flag("--whole-bag", &whole_bag);
  try
  {
    if (!cli.parse(argc, argv))
      return 0;
    if (in.empty() || topic.empty())
      throw pbc::UsageError("--in and a non-empty --imu-topic are required");
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "bag_read_floor: " << e.what() << "\n" << cli.usage();
    return 2;
  }
  try
  {
    const auto start = std::chrono::steady_clock::now();
    rosbag::Bag bag(in, rosbag::bagmode::Read);
    // compensate_bag accepts "imu/data" and "/imu/data" for the same topic.
    const std::string absolute = topic.front() == '/' ? topic : "/" + topic;
    std::unique_ptr<rosbag::View> view =
        whole_bag ? std::make_unique<rosbag::View>(bag)
                  : std::make_unique<rosbag::View>(bag, rosbag::TopicQuery({ topic, absolute }));
    std::int64_t messages = 0, read = 0;
    double checksum = 0.0;
    std::vector<std::uint8_t> bytes;
    for (const rosbag::MessageInstance& m : *view)
    {
      ++read;
      const std::string& t = m.getTopic();
      if (t != topic && t != absolute)
      {
        bytes.resize(m.size());
        ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
        m.write(stream);
        checksum += bytes.empty() ? 0.0 : bytes.back();
        continue;
      }
      const sensor_msgs::Imu::ConstPtr imu = m.instantiate<sensor_msgs::Imu>();
      if (!imu)
      {
        throw std::runtime_error("topic '" + t + "' holds " + m.getDataType() + ", not sensor_msgs/Imu");
      }
      checksum += imu->linear_acceleration.z;
      ++messages;
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "messages=" << messages << " wall_s=" << wall << " messages_per_s=" << messages / wall
              << " read=" << read << " checksum=" << checksum << std::endl;
  }
  catch (const std::exception& e)
  {
    std::cerr << "bag_read_floor: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
