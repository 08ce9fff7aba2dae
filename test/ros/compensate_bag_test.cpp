// compensate_bag end to end, without a master: runs the installed-style binary on the simulated
// paper bench bag and reads the bag it writes; --outputs and --compression (topics written, chunk
// compression, identical message bytes, readable by rosbag's Python reader too); the IMU's
// mounting from the bag's /tf_static (an IMU yawed 90 deg gives the same outputs); the batch
// one-liner of docs/batch.md and its Slurm script over a folder of bags; bags whose chunks
// overlap in time (merged by BagReader, or read through rosbag) give the same outputs; then the
// error paths (missing input, --out equal to --in, bad parameter files, missing topic, unknown
// output or compression): non-zero exit, a message naming the problem, and no output file.
#include <sys/stat.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <std_msgs/String.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_msgs/TFMessage.h>

#include "../common/shell.h"
#include "periodic_bias_compensation/BiasState.h"
#include "periodic_bias_compensation/ros/bag_reader.h"

namespace
{
using pbc_test::CommandResult;
using pbc_test::shell;

CommandResult run(const std::string& args)
{
  return shell(std::string(PBC_COMPENSATE_BAG) + " " + args);
}

bool exists(const std::string& path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

class CompensateBag : public testing::Test
{
protected:
  void SetUp() override
  {
    char pattern[] = "/tmp/compensate_bag_test.XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override
  {
    std::system(("rm -rf " + dir_).c_str());
  }
  std::string writeFile(const std::string& name, const std::string& content)
  {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << content;
    return path;
  }
  /// No output and no leftover temporary file in the directory.
  void expectNothingWritten(const std::string& out)
  {
    EXPECT_FALSE(exists(out)) << out << " was created";
    const CommandResult ls = shell("ls " + dir_ + " | grep partial");
    EXPECT_TRUE(ls.output.empty()) << "temporary file left: " << ls.output;
  }
  std::string dir_;
};

using Positions = std::map<std::int64_t, std::array<double, 3>>;

/// Every message of a bag as its serialised bytes with its time, by topic (leading '/' removed).
using Contents = std::map<std::string, std::vector<std::pair<std::uint64_t, std::vector<std::uint8_t>>>>;

Contents readContents(const std::string& path)
{
  Contents contents;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
  {
    std::string topic = m.getTopic();
    if (!topic.empty() && topic.front() == '/')
    {
      topic.erase(0, 1);
    }
    std::vector<std::uint8_t> bytes(m.size());
    ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    m.write(stream);
    contents[topic].emplace_back(m.getTime().toNSec(), std::move(bytes));
  }
  return contents;
}

/// Writes the IMU messages of `source` (its first `seconds`) to `path`, each changed by `change`,
/// after `tf_static` on /tf_static when it holds transforms.
void copyImu(const std::string& source, const std::string& path, const std::function<void(sensor_msgs::Imu*)>& change,
             const tf2_msgs::TFMessage& tf_static = {}, double seconds = std::numeric_limits<double>::infinity())
{
  rosbag::Bag in(source, rosbag::bagmode::Read);
  rosbag::View imu(in, rosbag::TopicQuery(std::vector<std::string>{ "imu/data", "/imu/data" }));
  rosbag::Bag out(path, rosbag::bagmode::Write);
  if (!tf_static.transforms.empty())
  {
    out.write("/tf_static", imu.getBeginTime(), tf_static);
  }
  for (const rosbag::MessageInstance& m : imu)
  {
    if ((m.getTime() - imu.getBeginTime()).toSec() > seconds)
    {
      break;
    }
    sensor_msgs::Imu message = *m.instantiate<sensor_msgs::Imu>();
    change(&message);
    out.write(m.getTopic(), m.getTime(), message);
  }
}

/// Pose of every odometry message of a bag by topic (leading '/' removed) and stamp [ns].
struct Pose
{
  std::array<double, 3> position;
  tf2::Quaternion orientation;
};
std::map<std::string, std::map<std::uint64_t, Pose>> readPoses(const std::string& path)
{
  std::map<std::string, std::map<std::uint64_t, Pose>> poses;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
  {
    if (const auto odom = m.instantiate<nav_msgs::Odometry>())
    {
      const auto& p = odom->pose.pose.position;
      const auto& q = odom->pose.pose.orientation;
      poses[m.getTopic().substr(m.getTopic().front() == '/' ? 1 : 0)][odom->header.stamp.toNSec()] =
          Pose{ { p.x, p.y, p.z }, tf2::Quaternion(q.x, q.y, q.z, q.w) };
    }
  }
  return poses;
}

/// Largest position difference [m] and rotation between the orientations [rad] of `topic` in
/// two bags (infinite when their stamps differ).
std::pair<double, double> largestDifference(const std::string& a, const std::string& b, const std::string& topic)
{
  const auto pa = readPoses(a)[topic], pb = readPoses(b)[topic];
  double position = 0.0, angle = 0.0;
  if (pa.empty() || pa.size() != pb.size())
  {
    return { INFINITY, INFINITY };
  }
  for (const auto& [stamp, pose] : pa)
  {
    const auto other = pb.find(stamp);
    if (other == pb.end())
    {
      return { INFINITY, INFINITY };
    }
    const auto& p = pose.position;
    const auto& q = other->second.position;
    position = std::max(position, std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
    angle = std::max(angle, 2.0 * std::acos(std::min(1.0, std::abs(pose.orientation.dot(other->second.orientation)))));
  }
  return { position, angle };
}

/// The bench bag's IMU as if mounted yawed by 90 deg about base_link's z: its frame imu_yawed,
/// whose axes are base_link's turned by +90 deg; with that transform on /tf_static if asked.
std::string yawedImuBag(const std::string& path, bool with_tf_static)
{
  tf2::Quaternion base_from_imu;
  base_from_imu.setRPY(0.0, 0.0, M_PI / 2);
  tf2_msgs::TFMessage tf_static;
  if (with_tf_static)
  {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "base_link";
    t.child_frame_id = "imu_yawed";
    t.transform.rotation.x = base_from_imu.x();
    t.transform.rotation.y = base_from_imu.y();
    t.transform.rotation.z = base_from_imu.z();
    t.transform.rotation.w = base_from_imu.w();
    tf_static.transforms.push_back(t);
  }
  const auto toImu = [&base_from_imu](geometry_msgs::Vector3* v) {
    const tf2::Vector3 r = tf2::quatRotate(base_from_imu.inverse(), tf2::Vector3(v->x, v->y, v->z));
    v->x = r.x();
    v->y = r.y();
    v->z = r.z();
  };
  copyImu(
      PBC_BENCH_BAG, path,
      [&](sensor_msgs::Imu* m) {
        m->header.frame_id = "imu_yawed";
        toImu(&m->linear_acceleration);
        toImu(&m->angular_velocity);
        auto& q = m->orientation;
        const tf2::Quaternion level_from_imu =
            tf2::Quaternion(q.x, q.y, q.z, q.w) * base_from_imu;  // level <- base <- imu
        q.x = level_from_imu.x();
        q.y = level_from_imu.y();
        q.z = level_from_imu.z();
        q.w = level_from_imu.w();
      },
      tf_static);
  return path;
}

/// The compression named in each chunk header of a bag file ("compression=NAME" fields).
std::map<std::string, int> chunkCompressions(const std::string& path)
{
  std::ifstream file(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  std::map<std::string, int> found;
  for (const char* name : { "none", "lz4", "bz2" })
  {
    const std::string field = std::string("compression=") + name;
    for (std::size_t at = bytes.find(field); at != std::string::npos; at = bytes.find(field, at + 1))
    {
      ++found[name];
    }
  }
  return found;
}
}  // namespace

TEST_F(CompensateBag, BenchBagEndToEnd)
{
  const std::string out = dir_ + "/out.bag";
  const CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out);
  ASSERT_EQ(r.status, 0) << r.output;

  rosbag::Bag bag(out, rosbag::bagmode::Read);
  std::map<std::string, Positions> tracks;
  std::size_t bias_states = 0;
  std::size_t nonfinite = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
  {
    std::string topic = m.getTopic();
    if (!topic.empty() && topic.front() == '/')
    {
      topic.erase(0, 1);
    }
    if (const auto odom = m.instantiate<nav_msgs::Odometry>())
    {
      const auto& p = odom->pose.pose.position;
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      {
        ++nonfinite;
      }
      tracks[topic][static_cast<std::int64_t>(odom->header.stamp.toNSec())] = { p.x, p.y, p.z };
    }
    else if (const auto bias = m.instantiate<periodic_bias_compensation::BiasState>())
    {
      ++bias_states;
      EXPECT_EQ(bias->mode, "default");
    }
  }
  EXPECT_EQ(nonfinite, 0u);
  const Positions& filtered = tracks["odometry/filtered"];
  const Positions& wave = tracks["odometry/wave"];
  const Positions& slow_truth = tracks["ground_truth/slow"];
  const Positions& wave_truth = tracks["ground_truth/wave"];
  ASSERT_FALSE(slow_truth.empty()) << "ground_truth/slow not copied";
  ASSERT_FALSE(wave_truth.empty()) << "ground_truth/wave not copied";
  EXPECT_FALSE(tracks["ground_truth/odometry"].empty()) << "ground_truth/odometry not copied";
  EXPECT_EQ(filtered.size(), slow_truth.size()) << "one output per IMU message expected";
  EXPECT_EQ(wave.size(), slow_truth.size());
  EXPECT_EQ(bias_states, slow_truth.size());

  // Same accuracy targets as the node (bag_accuracy.cpp): 0.06 m, 10 % wave RMS after 20 s.
  ASSERT_FALSE(filtered.empty());
  const auto& [stamp, p] = *filtered.rbegin();
  const auto& truth = slow_truth.at(stamp);
  const double final_error = std::hypot(p[0] - truth[0], p[1] - truth[1], p[2] - truth[2]);
  const double t0 = slow_truth.begin()->first * 1e-9;
  double err2 = 0.0;
  double truth2 = 0.0;
  for (const auto& [s, w] : wave)
  {
    if (s * 1e-9 - t0 < 20.0)
    {
      continue;
    }
    const auto& g = wave_truth.at(s);
    err2 += std::pow(w[0] - g[0], 2) + std::pow(w[1] - g[1], 2) + std::pow(w[2] - g[2], 2);
    truth2 += g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  }
  const double fraction = std::sqrt(err2 / truth2);
  std::printf("[compensate_bag] final filtered position error %.4f m, wave RMS error %.1f %% of truth RMS\n",
              final_error, 100.0 * fraction);
  EXPECT_LT(final_error, 0.06);
  EXPECT_LT(fraction, 0.10);
}

TEST_F(CompensateBag, OutputsChoosesTheTopicsWritten)
{
  const std::string all = dir_ + "/all.bag";
  CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + all);
  ASSERT_EQ(r.status, 0) << r.output;
  // The progress report ends with a line for the whole bag, which stays.
  EXPECT_NE(r.output.find("compensate_bag: 100% ("), std::string::npos) << r.output;
  const Contents everything = readContents(all);
  ASSERT_EQ(everything.size(), 6u);
  {
    // Every topic written absolute, as rosbag record names them: outputs and copies alike.
    rosbag::Bag bag(all, rosbag::bagmode::Read);
    for (const rosbag::ConnectionInfo* c : rosbag::View(bag).getConnections())
    {
      EXPECT_EQ(c->topic.front(), '/') << c->topic;
    }
  }

  const std::string filtered = dir_ + "/filtered.bag";
  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + filtered + " --outputs filtered");
  ASSERT_EQ(r.status, 0) << r.output;
  const Contents only_filtered = readContents(filtered);
  ASSERT_EQ(only_filtered.size(), 1u) << "topics other than odometry/filtered written";
  ASSERT_EQ(only_filtered.count("odometry/filtered"), 1u);
  EXPECT_EQ(only_filtered.at("odometry/filtered"), everything.at("odometry/filtered"));

  const std::string some = dir_ + "/some.bag";
  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + some + " --outputs bias,ground_truth,wave");
  ASSERT_EQ(r.status, 0) << r.output;
  const Contents chosen = readContents(some);
  for (const char* topic :
       { "bias_state", "odometry/wave", "ground_truth/slow", "ground_truth/wave", "ground_truth/odometry" })
  {
    ASSERT_EQ(chosen.count(topic), 1u) << topic << " missing";
    EXPECT_EQ(chosen.at(topic), everything.at(topic)) << topic << " differs from the default run";
  }
  EXPECT_EQ(chosen.count("odometry/filtered"), 0u);
  EXPECT_EQ(chosen.size(), 5u);
}

TEST_F(CompensateBag, CompressionOptionsGiveTheSameMessages)
{
  std::map<std::string, Contents> contents;
  for (const std::string compression : { "none", "lz4", "bz2" })
  {
    const std::string out = dir_ + "/" + compression + ".bag";
    const CommandResult r =
        run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --compression " + compression);
    ASSERT_EQ(r.status, 0) << r.output;
    const std::map<std::string, int> chunks = chunkCompressions(out);
    ASSERT_EQ(chunks.size(), 1u) << compression << ": chunks of several compressions";
    EXPECT_EQ(chunks.begin()->first, compression);
    EXPECT_GT(chunks.begin()->second, 1);
    contents[compression] = readContents(out);
    EXPECT_EQ(contents[compression].size(), 6u) << compression;

    // rosbag's Python reader parses every record header itself (the C++ reader trusts the index).
    const CommandResult python = shell(
        "/usr/bin/python3 -c \"import rosbag, sys; b = rosbag.Bag(sys.argv[1]); "
        "print('read', sum(1 for _ in b.read_messages(raw=True)))\" " +
        out);
    if (python.output.find("No module named") == std::string::npos)
    {
      std::size_t total = 0;
      for (const auto& [topic, messages] : contents[compression])
      {
        total += messages.size();
      }
      EXPECT_EQ(python.status, 0) << python.output;
      EXPECT_NE(python.output.find("read " + std::to_string(total)), std::string::npos) << python.output;
    }
  }
  EXPECT_EQ(contents["none"], contents["lz4"]);
  EXPECT_EQ(contents["none"], contents["bz2"]);

  // Its own output is a bag compensate_bag reads (the structure check passes): refused only for
  // having no IMU topic.
  const CommandResult again = run("--in " + dir_ + "/lz4.bag --out " + dir_ + "/again.bag");
  EXPECT_EQ(again.status, 1);
  EXPECT_NE(again.output.find("no topic 'imu/data'"), std::string::npos) << again.output;
}

TEST_F(CompensateBag, ModeAndParameterFile)
{
  const std::string out = dir_ + "/paper.bag";
  const CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --mode paper --params " +
                              PBC_SOURCE_DIR + "/config/compensator.yaml");
  ASSERT_EQ(r.status, 0) << r.output;
  rosbag::Bag bag(out, rosbag::bagmode::Read);
  std::size_t n = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/bias_state")))
  {
    const auto bias = m.instantiate<periodic_bias_compensation::BiasState>();
    ASSERT_TRUE(bias);
    EXPECT_EQ(bias->mode, "paper");
    ++n;
  }
  EXPECT_GT(n, 0u);
}

TEST_F(CompensateBag, TunedGainsFileLoadsAsParameters)
{
  const std::string out = dir_ + "/out.bag";
  const std::string gains = dir_ + "/gains.yaml";
  const CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --tune-gains " + gains);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("RMS of the slow motion"), std::string::npos) << r.output;
  std::ifstream file(gains);
  const std::string yaml((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  for (const char* key : { "alpha_v_x", "beta_p_z", "mode: paper" })
  {
    EXPECT_NE(yaml.find(key), std::string::npos) << key << " missing from\n" << yaml;
  }

  // The file is a parameter file: compensate_bag runs in paper mode with it.
  const std::string paper = dir_ + "/paper.bag";
  const CommandResult again = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + paper + " --params " + gains);
  ASSERT_EQ(again.status, 0) << again.output;
  rosbag::Bag bag(paper, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/bias_state"));
  ASSERT_NE(view.begin(), view.end());
  EXPECT_EQ(view.begin()->instantiate<periodic_bias_compensation::BiasState>()->mode, "paper");
}

TEST_F(CompensateBag, TuneGainsRefusesToOverwriteTheOutput)
{
  const std::string out = dir_ + "/out.bag";
  const CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --tune-gains " + out);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("--tune-gains '" + out + "' is the same file as --out"), std::string::npos) << r.output;
  expectNothingWritten(out);
}

TEST_F(CompensateBag, MountingFromTfStaticGivesTheAlignedOutputs)
{
  // The bench bag's IMU is in imu_link, aligned with base_link (no transform in the bag).
  const std::string aligned = dir_ + "/aligned.bag";
  CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + aligned);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("no imu_link -> base_link transform in the bag: taken as aligned"), std::string::npos)
      << r.output;

  const std::string yawed = yawedImuBag(dir_ + "/yawed.bag", true);
  const std::string compensated = dir_ + "/yawed_out.bag";
  r = run("--in " + yawed + " --out " + compensated);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("mounting: imu_yawed -> base_link from /tf_static, rpy 0 0 1.571 rad"), std::string::npos)
      << r.output;
  for (const char* topic : { "odometry/filtered", "odometry/wave" })
  {
    const auto [position, angle] = largestDifference(aligned, compensated, topic);
    std::printf("[compensate_bag] IMU yawed 90 deg with /tf_static: %s differs by up to %.2e m, %.2e rad\n", topic,
                position, angle);
    EXPECT_LT(position, 1e-3) << topic;
    EXPECT_LT(angle, 0.01) << topic;
  }
}

TEST_F(CompensateBag, ChunksOutOfTimeOrderGiveTheSameOutputs)
{
  // BagReader reads a bag whose chunks follow one another in time, and one whose last chunk
  // holds its earliest message (it opens the chunks by start time); rosbag::View one with more
  // chunks overlapping in time than BagReader holds. The same IMU messages and /tf_static give the same outputs, byte for
  // byte, and the same mounting.
  const std::string ordered = yawedImuBag(dir_ + "/ordered.bag", true);
  const std::string merged = yawedImuBag(dir_ + "/merged.bag", true);
  const std::string many = yawedImuBag(dir_ + "/many.bag", true);
  for (const std::string& path : { merged, many })
  {
    rosbag::Bag bag(path, rosbag::bagmode::Append);
    bag.setChunkThreshold(1);  // a chunk per message
    const int notes = path == many ? periodic_bias_compensation::BagReader::kMaxOpenChunks + 1 : 1;
    for (int i = 0; i < notes; ++i)
    {
      std_msgs::String note;
      note.data = "written last, stamped first";
      bag.write("/note", ros::Time(1.0), note);
    }
  }
  ASSERT_TRUE(periodic_bias_compensation::BagReader(ordered).usable());
  ASSERT_TRUE(periodic_bias_compensation::BagReader(merged).usable());
  ASSERT_FALSE(periodic_bias_compensation::BagReader(many).usable());
  std::map<std::string, Contents> outputs;
  for (const std::string& in : { ordered, merged, many })
  {
    const std::string out = in + ".out.bag";
    const CommandResult r = run("--in " + in + " --out " + out);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("mounting: imu_yawed -> base_link from /tf_static"), std::string::npos) << r.output;
    outputs[in] = readContents(out);
  }
  for (const char* topic : { "odometry/filtered", "odometry/wave", "bias_state" })
  {
    ASSERT_GT(outputs[ordered][topic].size(), 1000u) << topic;
    EXPECT_TRUE(outputs[ordered][topic] == outputs[merged][topic]) << topic << " differs when merged";
    EXPECT_TRUE(outputs[ordered][topic] == outputs[many][topic]) << topic << " differs through rosbag";
  }
}

TEST_F(CompensateBag, MountingWithoutTransformOrWithIdentityMountingIsAligned)
{
  const std::string aligned = dir_ + "/aligned.bag";
  CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + aligned + " --outputs filtered");
  ASSERT_EQ(r.status, 0) << r.output;

  // The same yawed IMU without /tf_static: taken as aligned, so its outputs are turned.
  const std::string untold = yawedImuBag(dir_ + "/untold.bag", false);
  r = run("--in " + untold + " --out " + dir_ + "/untold_out.bag --outputs filtered");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("no imu_yawed -> base_link transform in the bag: taken as aligned"), std::string::npos)
      << r.output;
  EXPECT_GT(largestDifference(aligned, dir_ + "/untold_out.bag", "odometry/filtered").second, 1.0);

  // identity_mounting: true skips the lookup, also with the transform in the bag.
  const std::string told = yawedImuBag(dir_ + "/told.bag", true);
  r = run("--in " + told + " --out " + dir_ + "/told_out.bag --outputs filtered --params " +
          writeFile("identity.yaml", "identity_mounting: true\n"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("mounting: identity_mounting: imu_yawed taken as aligned with base_link"), std::string::npos)
      << r.output;
  EXPECT_GT(largestDifference(aligned, dir_ + "/told_out.bag", "odometry/filtered").second, 1.0);
}

/// The line of docs/batch.md's code blocks that runs `tool` through GNU parallel ("" if none).
std::string documentedParallelLine(const std::string& tool)
{
  std::ifstream doc(std::string(PBC_SOURCE_DIR) + "/docs/batch.md");
  for (std::string line; std::getline(doc, line);)
  {
    if (line.rfind("    ", 0) == 0 && line.find(" parallel ") != std::string::npos &&
        line.find(" " + tool + " ") != std::string::npos)
    {
      return line.substr(4);
    }
  }
  return "";
}

TEST_F(CompensateBag, DocumentedBatchRunsOverAFolderOfBags)
{
  if (shell("command -v parallel").status != 0)
  {
    GTEST_SKIP() << "GNU parallel is not installed (Debian package parallel, scripts/setup): the one-liner of "
                    "docs/batch.md is not run";
  }
  std::string line = documentedParallelLine("compensate_bag");
  ASSERT_FALSE(line.empty()) << "no parallel ... compensate_bag line in docs/batch.md";
  // The tool built here (rosrun finds the same one when the workspace is sourced).
  const std::string rosrun = "rosrun periodic_bias_compensation compensate_bag";
  ASSERT_NE(line.find(rosrun), std::string::npos) << line;
  line.replace(line.find(rosrun), rosrun.size(), PBC_COMPENSATE_BAG);
  const auto keep = [](sensor_msgs::Imu*) {};
  ASSERT_EQ(std::system(("mkdir -p " + dir_ + "/bags " + dir_ + "/mixed").c_str()), 0);
  copyImu(PBC_BENCH_BAG, dir_ + "/bags/first.bag", keep, {}, 10.0);
  copyImu(PBC_BENCH_BAG, dir_ + "/bags/second.bag", keep, {}, 10.0);
  CommandResult r = shell("cd " + dir_ + "/bags && " + line);
  EXPECT_EQ(r.status, 0) << line << "\n" << r.output;
  EXPECT_TRUE(exists(dir_ + "/bags/compensated/first.bag")) << r.output;
  EXPECT_TRUE(exists(dir_ + "/bags/compensated/second.bag")) << r.output;

  // A broken bag among them: parallel's status counts the failed job, the joblog has its status 1.
  copyImu(PBC_BENCH_BAG, dir_ + "/mixed/good.bag", keep, {}, 10.0);
  writeFile("mixed/broken.bag", "#ROSBAG V2.0\n");
  r = shell("cd " + dir_ + "/mixed && " + line);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(exists(dir_ + "/mixed/compensated/good.bag"));
  EXPECT_FALSE(exists(dir_ + "/mixed/compensated/broken.bag"));
  const CommandResult exitvals = shell("cut -f7,9 " + dir_ + "/mixed/compensated/joblog.tsv | sort");
  EXPECT_NE(exitvals.output.find("1\t" + std::string(PBC_COMPENSATE_BAG) + " --in broken.bag"), std::string::npos)
      << exitvals.output;

  // The Slurm array script, run as task 1 would be (the second bag in file-name order).
  const std::string setup = std::string(PBC_CATKIN_DEVEL) + "/setup.bash";
  if (exists(setup))
  {
    const auto task = [&](int id) {
      return shell("cd " + dir_ + "/bags && PBC_WS=" + PBC_CATKIN_DEVEL + "/.. SLURM_ARRAY_TASK_ID=" +
                   std::to_string(id) + " bash " + PBC_SOURCE_DIR + "/scripts/slurm_compensate_bags slurm");
    };
    r = task(1);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(exists(dir_ + "/bags/slurm/second.bag")) << r.output;
    EXPECT_FALSE(exists(dir_ + "/bags/slurm/first.bag"));
    r = task(2);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("holds 2 bags"), std::string::npos) << r.output;
  }
}

TEST_F(CompensateBag, MissingInputFails)
{
  const std::string out = dir_ + "/out.bag";
  const CommandResult r = run("--in " + dir_ + "/no_such.bag --out " + out);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("no_such.bag"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  expectNothingWritten(out);
}

TEST_F(CompensateBag, NeverOverwritesInput)
{
  const std::string in = dir_ + "/in.bag";
  ASSERT_EQ(std::system((std::string("cp ") + PBC_BENCH_BAG + " " + in).c_str()), 0);
  struct stat before;
  ASSERT_EQ(::stat(in.c_str(), &before), 0);
  const CommandResult r = run("--in " + in + " --out " + dir_ + "/./in.bag");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("overwritten"), std::string::npos) << r.output;
  struct stat after;
  ASSERT_EQ(::stat(in.c_str(), &after), 0);
  EXPECT_EQ(before.st_size, after.st_size);
  EXPECT_EQ(before.st_mtime, after.st_mtime);
}

TEST_F(CompensateBag, BadParameterFilesNameTheKey)
{
  const std::string out = dir_ + "/out.bag";
  const std::string unknown = writeFile("unknown.yaml", "alpha_v_x: 0.4\nalpah_p_x: 0.3\n");
  CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --params " + unknown);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("alpah_p_x"), std::string::npos) << r.output;
  expectNothingWritten(out);

  const std::string type = writeFile("type.yaml", "fft_window: long\n");
  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --params " + type);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("fft_window"), std::string::npos) << r.output;
  expectNothingWritten(out);

  const std::string unstable = writeFile("unstable.yaml", "beta_v_x: 40.0\n");
  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --params " + unstable);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("beta_v_x"), std::string::npos) << r.output;
  expectNothingWritten(out);

  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --params " + dir_ + "/absent.yaml");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("absent.yaml"), std::string::npos) << r.output;
  expectNothingWritten(out);
}

TEST_F(CompensateBag, MissingTopicAndBadArguments)
{
  const std::string out = dir_ + "/out.bag";
  CommandResult r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --imu-topic imu/raw");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("imu/raw"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("imu/data"), std::string::npos) << "the topics present should be listed: " << r.output;
  expectNothingWritten(out);

  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --mode fast");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("--mode"), std::string::npos) << r.output;
  expectNothingWritten(out);

  r = run("--in " + std::string(PBC_BENCH_BAG));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("usage"), std::string::npos) << r.output;

  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --outputs filtered,raw");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("unknown output 'raw'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("filtered, wave, bias, ground_truth"), std::string::npos) << r.output;
  expectNothingWritten(out);

  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --outputs ''");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("--outputs"), std::string::npos) << r.output;
  expectNothingWritten(out);

  r = run(std::string("--in ") + PBC_BENCH_BAG + " --out " + out + " --compression zstd");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("--compression"), std::string::npos) << r.output;
  expectNothingWritten(out);
}

TEST_F(CompensateBag, AccelerationInGIsRefused)
{
  // A driver publishing g instead of m/s^2 (REP-145): outputs would be ten times too small, so
  // the bag is refused with the reason, and nothing is written.
  const std::string in = dir_ + "/in_g.bag", out = dir_ + "/out.bag";
  {
    rosbag::Bag bag(in, rosbag::bagmode::Write);
    for (int k = 0; k < 500; ++k)
    {
      sensor_msgs::Imu m;
      m.header.stamp.fromSec(100.0 + k * 0.01);
      m.header.frame_id = "base_link";
      m.linear_acceleration.z = 1.0;
      m.orientation.w = 1.0;
      bag.write("imu/data", m.header.stamp, m);
    }
  }
  const CommandResult r = run("--in " + in + " --out " + out);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("looks like g"), std::string::npos) << r.output;
  expectNothingWritten(out);
}

TEST_F(CompensateBag, BagEndingMidChunkIsRefusedWithAClearMessage)
{
  // A recording cut off (power loss, disk full): the bag ends in the middle of a chunk, with no
  // index. compensate_bag refuses it, says what happened and how to recover, writes nothing.
  std::ifstream source(PBC_BENCH_BAG, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(source)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 100000u);
  const std::string cut = dir_ + "/cut.bag";
  {
    std::ofstream(cut, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size() * 6 / 10));
  }
  const std::string out = dir_ + "/out.bag";
  CommandResult r = run("--in " + cut + " --out " + out);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("truncated or corrupt"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("rosbag reindex"), std::string::npos) << r.output;
  expectNothingWritten(out);

  // Corrupted in the middle (a chunk overwritten), index intact: refused the same way, no
  // partial output.
  std::string corrupt = bytes;
  for (std::size_t i = corrupt.size() / 2; i < corrupt.size() / 2 + 4096; ++i)
  {
    corrupt[i] = static_cast<char>(0xA5);
  }
  const std::string damaged = dir_ + "/damaged.bag";
  {
    std::ofstream(damaged, std::ios::binary).write(corrupt.data(), static_cast<std::streamsize>(corrupt.size()));
  }
  r = run("--in " + damaged + " --out " + out);
  if (r.status == 0)
  {
    // rosbag may read past damage inside message payloads (values, not structure): then the
    // output must still be complete and finite.
    rosbag::Bag bag(out, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/odometry/filtered")))
    {
      const auto odom = m.instantiate<nav_msgs::Odometry>();
      ASSERT_TRUE(odom);
      EXPECT_TRUE(std::isfinite(odom->pose.pose.position.x + odom->pose.pose.position.y + odom->pose.pose.position.z));
    }
  }
  else
  {
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("truncated or corrupt"), std::string::npos) << r.output;
    expectNothingWritten(out);
  }

  // The documented recovery: rosbag reindex keeps the messages before the cut; compensate_bag
  // then processes that part (partial output by the operator's choice, complete for what was kept).
  if (shell("command -v rosbag").status == 0)
  {
    const CommandResult reindex =
        shell("mkdir -p " + dir_ + "/re && cd " + dir_ + " && rosbag reindex --output-dir=" + dir_ + "/re cut.bag");
    const std::string recovered = dir_ + "/re/cut.bag";
    if (reindex.status == 0 && exists(recovered))
    {
      r = run("--in " + recovered + " --out " + out);
      ASSERT_EQ(r.status, 0) << r.output;
      rosbag::Bag bag(out, rosbag::bagmode::Read);
      const std::size_t n = rosbag::View(bag, rosbag::TopicQuery("/odometry/filtered")).size();
      rosbag::Bag full(PBC_BENCH_BAG, rosbag::bagmode::Read);
      const std::size_t total =
          rosbag::View(full, rosbag::TopicQuery(std::vector<std::string>{ "imu/data", "/imu/data" })).size();
      std::printf("[compensate_bag] bag cut at 60 %%, reindexed: %zu of %zu IMU messages compensated\n", n, total);
      EXPECT_GT(n, total / 4);
      EXPECT_LT(n, total);
    }
    else
    {
      std::printf("[compensate_bag] rosbag reindex unavailable here (%s): recovery not checked\n",
                  reindex.output.c_str());
    }
  }
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
