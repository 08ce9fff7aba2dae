// Every shipped scenario produces a bag that the compensator consumes. For each file
// of config/scenarios/: simulate_imu --duration 60 -> bag, compensate_bag -> bag, then read
// the output with the rosbag C++ API: one odometry/filtered per imu/data message (compensate_bag
// writes one per accepted sample and counts what it rejects), every value finite.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>

#include "../common/shell.h"

namespace fs = std::filesystem;

namespace
{
using pbc_test::CommandResult;
using pbc_test::shell;

bool finite(const nav_msgs::Odometry& o)
{
  const auto& p = o.pose.pose;
  const auto& t = o.twist.twist;
  const double values[] = { p.position.x,    p.position.y,    p.position.z, p.orientation.w, p.orientation.x,
                            p.orientation.y, p.orientation.z, t.linear.x,   t.linear.y,      t.linear.z,
                            t.angular.x,     t.angular.y,     t.angular.z };
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      return false;
    }
  }
  for (double v : o.pose.covariance)
  {
    if (!std::isfinite(v))
    {
      return false;
    }
  }
  for (double v : o.twist.covariance)
  {
    if (!std::isfinite(v))
    {
      return false;
    }
  }
  return true;
}

std::vector<std::string> shippedScenarios()
{
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(PBC_SCENARIO_DIR))
  {
    if (entry.path().extension() == ".yaml")
    {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

class ShippedBags : public testing::TestWithParam<std::string>
{
protected:
  void SetUp() override
  {
    char pattern[] = "/tmp/pbc_shipped_bags_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override
  {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string dir_;
};

TEST_P(ShippedBags, CompensatorConsumesSimulatedBag)
{
  const std::string scenario = GetParam();
  const std::string sim_bag = dir_ + "/sim.bag";
  const std::string out_bag = dir_ + "/out.bag";
  const CommandResult sim =
      shell(std::string(PBC_SIMULATE_IMU) + " --scenario " + scenario + " --out " + sim_bag + " --duration 60");
  ASSERT_EQ(sim.status, 0) << sim.output;
  const CommandResult comp = shell(std::string(PBC_COMPENSATE_BAG) + " --in " + sim_bag + " --out " + out_bag);
  ASSERT_EQ(comp.status, 0) << comp.output;

  std::size_t imu_count = 0;
  {
    rosbag::Bag bag(sim_bag, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{ "imu/data", "/imu/data" }));
    for (const rosbag::MessageInstance& m : view)
    {
      ASSERT_TRUE(m.instantiate<sensor_msgs::Imu>() != nullptr);
      ++imu_count;
    }
  }
  ASSERT_GT(imu_count, 0u) << scenario;

  std::size_t filtered = 0;
  std::size_t nonfinite = 0;
  {
    rosbag::Bag bag(out_bag, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{ "odometry/filtered", "/odometry/filtered" }));
    for (const rosbag::MessageInstance& m : view)
    {
      const nav_msgs::Odometry::ConstPtr odom = m.instantiate<nav_msgs::Odometry>();
      ASSERT_TRUE(odom != nullptr);
      ++filtered;
      nonfinite += finite(*odom) ? 0 : 1;
    }
  }
  // compensate_bag writes one odometry/filtered per accepted imu/data message; the shipped
  // scenarios have neither duplicate stamps nor non-finite values, so every message is accepted.
  EXPECT_EQ(filtered, imu_count) << scenario << "\n" << comp.output;
  EXPECT_EQ(nonfinite, 0u) << scenario;
}

std::string testName(const testing::TestParamInfo<std::string>& info)
{
  std::string name = fs::path(info.param).stem().string();
  for (char& c : name)
  {
    if (!std::isalnum(static_cast<unsigned char>(c)))
    {
      c = '_';
    }
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(EveryScenario, ShippedBags, testing::ValuesIn(shippedScenarios()), testName);

TEST(ShippedBagsList, ScenarioFolderIsNotEmpty)
{
  EXPECT_GE(shippedScenarios().size(), 1u);
}
}  // namespace

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
