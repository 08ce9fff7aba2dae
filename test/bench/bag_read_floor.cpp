// bag_read_floor: the floor of compensate_bag's speed, a loop that only reads a bag's IMU messages
// (rosbag::View on the topic, each instantiated as sensor_msgs::Imu, as compensate_bag does) and
// sums one field so the work cannot be dropped. Run by scripts/bench, not a test.
//
//   bag_read_floor --in IN.bag [--imu-topic imu/data]
//
// Output: one line "messages=N wall_s=S messages_per_s=R checksum=C".
#include <chrono>
#include <cstdint>
#include <iostream>
#include <stdexcept>
#include <string>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>

int main(int argc, char** argv)
{
  std::string in;
  std::string topic = "imu/data";
  for (int i = 1; i + 1 < argc; i += 2)
  {
    const std::string arg = argv[i];
    if (arg == "--in")
      in = argv[i + 1];
    else if (arg == "--imu-topic")
      topic = argv[i + 1];
  }
  if (in.empty() || argc % 2 == 0)
  {
    std::cerr << "usage: bag_read_floor --in IN.bag [--imu-topic imu/data]" << std::endl;
    return 2;
  }
  try
  {
    const auto start = std::chrono::steady_clock::now();
    rosbag::Bag bag(in, rosbag::bagmode::Read);
    // compensate_bag accepts "imu/data" and "/imu/data" for the same topic.
    const std::string absolute = topic.front() == '/' ? topic : "/" + topic;
    rosbag::View view(bag, rosbag::TopicQuery({ topic, absolute }));
    std::int64_t messages = 0;
    double checksum = 0.0;
    for (const rosbag::MessageInstance& m : view)
    {
      const sensor_msgs::Imu::ConstPtr imu = m.instantiate<sensor_msgs::Imu>();
      if (!imu)
      {
        throw std::runtime_error("topic '" + m.getTopic() + "' holds " + m.getDataType() + ", not sensor_msgs/Imu");
      }
      checksum += imu->linear_acceleration.z;
      ++messages;
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "messages=" << messages << " wall_s=" << wall << " messages_per_s=" << messages / wall
              << " checksum=" << checksum << std::endl;
  }
  catch (const std::exception& e)
  {
    std::cerr << "bag_read_floor: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
