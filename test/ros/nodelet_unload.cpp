// The compensator nodelet unloaded while samples arrive, then loaded again, several times, into
// the same manager (nodelet_unload.test): the unload waits for the sample being handled and
// drops the ones queued, so the manager survives and every load answers again. Both ways imu/data
// is served: a thread of the nodelet's own (~imu_thread, the default) and the manager's queues.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nodelet/NodeletList.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>

#include "fault_helpers.h"

namespace
{
const char* kName = "/compensator";

bool load()
{
  nodelet::NodeletLoad srv;
  srv.request.name = kName;
  srv.request.type = "periodic_bias_compensation/CompensatorNodelet";
  return ros::service::call("/manager/load_nodelet", srv) && srv.response.success;
}

bool unload()
{
  nodelet::NodeletUnload srv;
  srv.request.name = kName;
  return ros::service::call("/manager/unload_nodelet", srv) && srv.response.success;
}

/// The nodelets the manager holds; false when it does not answer.
bool listed(std::vector<std::string>* nodelets)
{
  nodelet::NodeletList srv;
  if (!ros::service::call("/manager/list", srv))
    return false;
  *nodelets = srv.response.nodelets;
  return true;
}
}  // namespace

TEST(NodeletUnload, UnloadWhileSamplesArriveLeavesTheManagerWorking)
{
  ros::NodeHandle nh;
  ASSERT_TRUE(ros::service::waitForService("/manager/load_nodelet", ros::Duration(30.0)));
  pbc_test::Observer observer(nh);
  pbc_test::ImuStream stream(nh);
  stream.rate = 1000.0;
  stream.amplitude = 0.3;
  stream.start();
  for (int cycle = 0; cycle < 6; ++cycle)
  {
    const bool own_thread = cycle % 2 == 0;
    SCOPED_TRACE("cycle " + std::to_string(cycle) + (own_thread ? ", own thread" : ", manager's queues"));
    ros::param::set(std::string(kName) + "/imu_thread", own_thread);
    ASSERT_TRUE(load()) << "the compensator did not load";
    ASSERT_TRUE(observer.waitForOdometry(500, 30.0)) << "no odometry/filtered after the load";
    // Unloaded in the middle of the stream: a sample is being handled or queued at that moment.
    ASSERT_TRUE(unload()) << "the compensator did not unload";
    std::vector<std::string> held;
    ASSERT_TRUE(listed(&held)) << "the manager does not answer after the unload";
    EXPECT_TRUE(held.empty()) << "the manager still holds " << held.front();
    ros::WallDuration(0.3).sleep();
    const std::size_t after_unload = observer.odometryCount();
    ros::WallDuration(0.5).sleep();
    EXPECT_EQ(observer.odometryCount(), after_unload) << "outputs continued after the unload";
  }
  EXPECT_EQ(observer.nonfinite(), 0u);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_nodelet_unload");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
