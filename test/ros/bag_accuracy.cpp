// Bag regression for the node and the nodelet: the paper bench bag (simulate_imu, scenario
// paper_bench) is replayed with --clock; this test compares the published outputs with the
// simulator's truth.
//   - final odometry/filtered position within ~position_tolerance [m] of ground_truth/slow
//   - odometry/wave follows ground_truth/wave: RMS of the 3-D error after ~wave_start [s] below
//     ~wave_rms_fraction of the RMS of the 3-D truth (an output stuck at zero gives 100 %)
//   - nothing published is NaN/Inf
// Private parameters: imu_frame, base_frame (static identity mounting published here),
// expected_duration [s] of bag time, timeout [s] of wall time, tolerances above.
#include <cmath>
#include <map>
#include <mutex>

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

namespace
{
struct Track
{
  std::map<std::int64_t, std::array<double, 3>> by_stamp;  ///< key: stamp [ns]
  std::size_t nonfinite = 0;
};

class Recorder
{
public:
  void add(const std::string& name, const nav_msgs::Odometry::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& p = msg->pose.pose.position;
    Track& track = tracks_[name];
    bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    for (double c : msg->pose.covariance)
    {
      finite = finite && std::isfinite(c);
    }
    for (double c : msg->twist.covariance)
    {
      finite = finite && std::isfinite(c);
    }
    if (!finite)
    {
      ++track.nonfinite;
      return;
    }
    track.by_stamp[static_cast<std::int64_t>(msg->header.stamp.toNSec())] = { p.x, p.y, p.z };
    last_ = ros::WallTime::now();
  }
  Track get(const std::string& name)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return tracks_[name];
  }
  ros::WallTime last()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_;
  }

private:
  std::mutex mutex_;
  std::map<std::string, Track> tracks_;
  ros::WallTime last_;
};

double norm(const std::array<double, 3>& a)
{
  return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}
}  // namespace

TEST(BagAccuracy, FilteredAndWaveFollowTruth)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const double position_tolerance = pnh.param("position_tolerance", 0.06);
  const double wave_rms_fraction = pnh.param("wave_rms_fraction", 0.10);
  const double wave_start = pnh.param("wave_start", 20.0);
  const double expected_duration = pnh.param("expected_duration", 60.0);
  const double timeout = pnh.param("timeout", 150.0);

  tf2_ros::StaticTransformBroadcaster static_tf;
  geometry_msgs::TransformStamped mount;
  mount.header.frame_id = pnh.param<std::string>("base_frame", "base_link");
  mount.child_frame_id = pnh.param<std::string>("imu_frame", "imu_link");
  mount.transform.rotation.w = 1.0;
  static_tf.sendTransform(mount);

  Recorder recorder;
  std::vector<ros::Subscriber> subs;
  for (const std::string topic : { "odometry/filtered", "odometry/wave", "ground_truth/slow", "ground_truth/wave" })
  {
    subs.push_back(nh.subscribe<nav_msgs::Odometry>(
        topic, 20000, [&recorder, topic](const nav_msgs::Odometry::ConstPtr& msg) { recorder.add(topic, msg); }));
  }

  // Wait until the bag has been played: the filtered output reaches the end of the bag, or
  // nothing arrived for 5 s after something did.
  const ros::WallTime start = ros::WallTime::now();
  while (ros::ok() && (ros::WallTime::now() - start).toSec() < timeout)
  {
    ros::WallDuration(0.5).sleep();
    const Track filtered = recorder.get("odometry/filtered");
    const Track truth = recorder.get("ground_truth/slow");
    if (!filtered.by_stamp.empty() && !truth.by_stamp.empty())
    {
      const double span = (filtered.by_stamp.rbegin()->first - truth.by_stamp.begin()->first) * 1e-9;
      if (span >= expected_duration - 0.1 || (ros::WallTime::now() - recorder.last()).toSec() > 5.0)
      {
        break;
      }
    }
  }
  ros::WallDuration(1.0).sleep();

  const Track filtered = recorder.get("odometry/filtered");
  const Track wave = recorder.get("odometry/wave");
  const Track slow_truth = recorder.get("ground_truth/slow");
  const Track wave_truth = recorder.get("ground_truth/wave");
  ASSERT_FALSE(filtered.by_stamp.empty()) << "no odometry/filtered received";
  ASSERT_FALSE(wave.by_stamp.empty()) << "no odometry/wave received";
  ASSERT_FALSE(slow_truth.by_stamp.empty()) << "no ground_truth/slow received";
  ASSERT_FALSE(wave_truth.by_stamp.empty()) << "no ground_truth/wave received";
  EXPECT_EQ(filtered.nonfinite, 0u);
  EXPECT_EQ(wave.nonfinite, 0u);

  const double t0 = slow_truth.by_stamp.begin()->first * 1e-9;
  const double covered = filtered.by_stamp.rbegin()->first * 1e-9 - t0;
  EXPECT_GE(covered, expected_duration - 0.5) << "the output stopped before the end of the bag";
  // Every IMU message of the bag has a truth message with the same stamp.
  EXPECT_GE(filtered.by_stamp.size(), 0.98 * slow_truth.by_stamp.size()) << "outputs were lost";

  // Final filtered position against the slow truth at the same stamp.
  const auto last = filtered.by_stamp.rbegin();
  const auto truth_it = slow_truth.by_stamp.find(last->first);
  ASSERT_NE(truth_it, slow_truth.by_stamp.end()) << "no truth at the stamp of the last output";
  const std::array<double, 3> err = { last->second[0] - truth_it->second[0], last->second[1] - truth_it->second[1],
                                      last->second[2] - truth_it->second[2] };
  const double final_error = norm(err);

  // Wave RMS error after wave_start.
  double err2 = 0.0;
  double truth2 = 0.0;
  std::size_t n = 0;
  for (const auto& [stamp, w] : wave.by_stamp)
  {
    if (stamp * 1e-9 - t0 < wave_start)
    {
      continue;
    }
    const auto it = wave_truth.by_stamp.find(stamp);
    if (it == wave_truth.by_stamp.end())
    {
      continue;
    }
    const std::array<double, 3> e = { w[0] - it->second[0], w[1] - it->second[1], w[2] - it->second[2] };
    err2 += norm(e) * norm(e);
    truth2 += norm(it->second) * norm(it->second);
    ++n;
  }
  ASSERT_GT(n, 100u) << "too few wave outputs after " << wave_start << " s matched the truth";
  const double wave_rms = std::sqrt(err2 / n);
  const double truth_rms = std::sqrt(truth2 / n);
  ASSERT_GT(truth_rms, 1e-4) << "the bag has no wave motion to follow";
  const double fraction = wave_rms / truth_rms;

  std::printf(
      "[bag_accuracy] final filtered position error %.4f m after %.1f s (tolerance %.3f m); "
      "wave RMS error %.4f m = %.1f %% of truth RMS %.4f m over %zu samples (limit %.0f %%)\n",
      final_error, covered, position_tolerance, wave_rms, 100.0 * fraction, truth_rms, n, 100.0 * wave_rms_fraction);
  RecordProperty("final_position_error_m", std::to_string(final_error));
  RecordProperty("wave_rms_error_percent", std::to_string(100.0 * fraction));
  EXPECT_LT(final_error, position_tolerance);
  EXPECT_LT(fraction, wave_rms_fraction);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bag_accuracy");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
