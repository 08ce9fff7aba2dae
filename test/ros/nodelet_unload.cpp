// The compensator nodelet unloaded while samples arrive, then loaded again, several times, into
// the same manager (nodelet_unload.test): the unload waits for the sample being handled and
// drops the ones queued, so the manager survives and every load answers again. Both ways imu/data
// is served: a thread of the nodelet's own (~imu_thread, the default) and the manager's queues;
// one load makes that thread real-time (~imu_thread_priority), another asks every CPU to wake at
// once (~cpu_wakeup_latency 0, withdrawn by the unload), as far as this machine allows.
#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/types.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nodelet/NodeletList.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/this_node.h>
#include <xmlrpcpp/XmlRpcClient.h>

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

/// The process id of the node `name` (its XML-RPC getPid); -1 when it does not answer.
pid_t nodePid(const std::string& name)
{
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = name;
  if (!ros::master::execute("lookupNode", args, result, payload, false))
    return -1;
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(static_cast<std::string>(payload), host, port))
    return -1;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue request;
  request[0] = ros::this_node::getName();
  if (!client.execute("getPid", request, result) || result.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      static_cast<int>(result[0]) != 1)
    return -1;
  return static_cast<pid_t>(static_cast<int>(result[2]));
}

/// The ids of the threads named pbc_imu in process `pid`.
std::vector<pid_t> imuThreads(pid_t pid)
{
  std::vector<pid_t> found;
  const std::string tasks = "/proc/" + std::to_string(pid) + "/task";
  DIR* dir = opendir(tasks.c_str());
  if (dir == nullptr)
    return found;
  while (const dirent* task = readdir(dir))
  {
    std::string name;
    std::getline(std::ifstream(tasks + "/" + task->d_name + "/comm"), name);
    if (name == "pbc_imu")
      found.push_back(static_cast<pid_t>(std::stol(task->d_name)));
  }
  closedir(dir);
  return found;
}

/// Whether a process of this user may make a thread SCHED_FIFO (tried on the calling thread, then
/// undone): the manager, started the same way, may then too.
bool realtimeAllowed()
{
  sched_param param{};
  param.sched_priority = 1;
  if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) != 0)
    return false;
  param.sched_priority = 0;
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
  return true;
}

/// The CPU wake-up latency limit the kernel honours now [us] (read from its PM QoS device, as
/// the kernel documents it, not through the code tested); nothing when this process may not both
/// read and write the device: the manager, started the same way, may then not write it either.
std::optional<std::int32_t> wakeupLimit()
{
  const char* device = "/dev/cpu_dma_latency";
  if (access(device, R_OK | W_OK) != 0)
    return std::nullopt;
  const int fd = open(device, O_RDONLY);
  if (fd < 0)
    return std::nullopt;
  std::int32_t limit = 0;
  const bool read_whole = read(fd, &limit, sizeof(limit)) == static_cast<ssize_t>(sizeof(limit));
  close(fd);
  return read_whole ? std::optional<std::int32_t>(limit) : std::nullopt;
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
  const bool realtime_allowed = realtimeAllowed();
  if (!wakeupLimit())
    std::cout << "/dev/cpu_dma_latency is not this user's to read and write: the wake-up latency request "
                 "is not checked\n";
  const pid_t manager = nodePid("/manager");
  ASSERT_GT(manager, 0) << "the manager's process id is not known";
  for (int cycle = 0; cycle < 6; ++cycle)
  {
    const bool own_thread = cycle % 2 == 0;
    const int priority = cycle == 2 ? 10 : 0;
    SCOPED_TRACE("cycle " + std::to_string(cycle) + (own_thread ? ", own thread" : ", manager's queues") +
                 ", priority " + std::to_string(priority));
    ros::param::set(std::string(kName) + "/imu_thread", own_thread);
    ros::param::set(std::string(kName) + "/imu_thread_priority", priority);
    const bool wakeup_request = cycle == 4;
    ros::param::set(std::string(kName) + "/cpu_wakeup_latency", wakeup_request ? 0.0 : -1.0);
    const std::optional<std::int32_t> limit_before = wakeupLimit();
    ASSERT_TRUE(load()) << "the compensator did not load";
    ASSERT_TRUE(observer.waitForOdometry(500, 30.0)) << "no odometry/filtered after the load";
    const std::vector<pid_t> threads = imuThreads(manager);
    ASSERT_EQ(threads.size(), own_thread ? 1u : 0u);
    if (own_thread)
    {
      // Refused, the thread runs as an ordinary one (and a WARN says why).
      const bool realtime = priority > 0 && realtime_allowed;
      sched_param param{};
      ASSERT_EQ(sched_getparam(threads[0], &param), 0);
      EXPECT_EQ(sched_getscheduler(threads[0]), realtime ? SCHED_FIFO : SCHED_OTHER);
      EXPECT_EQ(param.sched_priority, realtime ? priority : 0);
    }
    if (limit_before)
    {
      EXPECT_EQ(wakeupLimit(), wakeup_request ? 0 : *limit_before);
    }
    // Unloaded in the middle of the stream: a sample is being handled or queued at that moment.
    ASSERT_TRUE(unload()) << "the compensator did not unload";
    if (limit_before)
    {
      EXPECT_EQ(wakeupLimit(), *limit_before) << "the wake-up latency request outlived the unload";
    }
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
