// A process dies (SIGKILL, as on a crash) while IMU data flows: the nodelet manager
// (manager_restart.test: roslaunch respawns it, the loader node respawns and loads the
// compensator again) or the stand-alone compensator itself (manager_restart_standalone.test),
// named by the private parameter ~kill. Checks: outputs stop, then resume from a fresh
// estimator (calibrates again, diagnostics counters start over), never a NaN.
#include <signal.h>
#include <sys/types.h>

#include <gtest/gtest.h>
#include <ros/master.h>
#include <ros/network.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include "fault_helpers.h"

namespace
{
/// PID of a node through its XML-RPC API (getPid), -1 if unknown.
int nodePid(const std::string& node)
{
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, false) ||
      result.getType() != XmlRpc::XmlRpcValue::TypeArray || static_cast<int>(result[0]) != 1)
  {
    return -1;
  }
  std::string host;
  uint32_t port = 0;
  if (!ros::network::splitURI(static_cast<std::string>(result[2]), host, port))
  {
    return -1;
  }
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue pid_args, pid_result;
  pid_args[0] = ros::this_node::getName();
  if (!client.execute("getPid", pid_args, pid_result) || pid_result.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      static_cast<int>(pid_result[0]) != 1)
  {
    return -1;
  }
  return static_cast<int>(pid_result[2]);
}
}  // namespace

TEST(ManagerRestart, OutputsResumeFromAFreshEstimator)
{
  ros::NodeHandle nh;
  pbc_test::Observer observer(nh);
  pbc_test::ImuStream stream(nh);
  ASSERT_TRUE(stream.waitForSubscriber(30.0)) << "the compensator did not subscribe to imu/data";
  stream.amplitude = 0.3;
  stream.start();
  ASSERT_TRUE(observer.waitForOdometry(200, 30.0)) << "no odometry/filtered before the restart";
  pbc_test::Status s = observer.waitForStatus(
      [](const pbc_test::Status& st) {
        return st.values.count("calibration") && st.values.at("calibration").rfind("done", 0) == 0;
      },
      20.0);
  ASSERT_GE(s.level, 0) << "never calibrated before the restart";
  // Let the loader's bond with the manager form (heartbeats every second) before the crash.
  ros::WallDuration(5.0).sleep();
  // Messages counted by the compensator so far: a fresh one after the restart counts fewer.
  const pbc_test::Status before_kill = observer.last();
  const long received_before = before_kill.values.count("received") ? std::stol(before_kill.values.at("received"))
                                                                    : std::stol(s.values["received"]);
  const std::string victim = ros::NodeHandle("~").param<std::string>("kill", "/manager");
  const int pid = nodePid(victim);
  ASSERT_GT(pid, 0) << "no PID for " << victim;
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  // Outputs stop (the last queued messages may still arrive).
  ros::WallDuration(1.0).sleep();
  const std::size_t after_kill = observer.odometryCount();
  ros::WallDuration(1.0).sleep();
  EXPECT_LE(observer.odometryCount(), after_kill + 5) << "outputs continued with " << victim << " killed";

  // Respawned: outputs again, from a fresh estimator.
  ASSERT_TRUE(observer.waitForOdometry(200, 60.0)) << "no output after " << victim << " restarted";
  EXPECT_GT(nodePid(victim), 0);
  EXPECT_NE(nodePid(victim), pid) << victim << " was not restarted";
  s = observer.waitForStatus(
      [&](const pbc_test::Status& st) {
        return st.values.count("received") && std::stol(st.values.at("received")) < received_before &&
               st.values.count("calibration") && st.values.at("calibration").rfind("done", 0) == 0;
      },
      30.0);
  EXPECT_GE(s.level, 0) << "no diagnostics of a fresh, calibrated compensator after the restart";
  EXPECT_LT(s.level, diagnostic_msgs::DiagnosticStatus::ERROR) << s.message;
  stream.stop();
  EXPECT_EQ(observer.nonfinite(), 0u);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "manager_restart_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
