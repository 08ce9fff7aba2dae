// Wrapper pieces without a master: Imu -> ImuSample with a mounting rotation, the mounting
// looked up in a tf2 buffer (node and compensate_bag), Odometry covariances (never -1, unknown
// -> kUnknownCovariance), finite checks, the frame filter, the parameters read from YAML (unknown
// key, wrong type, invalid value named), the parameter tables against config/compensator.yaml
// (keys, defaults, [reconfigure] marks), cfg/Compensator.cfg (defaults, ranges, descriptions as
// compiled) and docs/ros_api.md (generated section), the reconfigure message round trip, and the
// raw double integration.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "periodic_bias_compensation/CompensatorConfig.h"
#include "periodic_bias_compensation/ros/conversions.h"
#include "periodic_bias_compensation/ros/mounting.h"
#include "periodic_bias_compensation/ros/parameter_reference.h"
#include "periodic_bias_compensation/ros/parameters.h"

using namespace periodic_bias_compensation;
using Tuning = periodic_bias_compensation_cfg::CompensatorConfig;

namespace
{
sensor_msgs::Imu levelImu()
{
  sensor_msgs::Imu msg;
  msg.header.stamp = ros::Time(1000.5);
  msg.header.frame_id = "imu_link";
  msg.linear_acceleration.x = 1.0;
  msg.linear_acceleration.z = kStandardGravity;
  msg.angular_velocity.x = 0.1;
  msg.orientation.w = 1.0;
  msg.orientation_covariance[0] = msg.orientation_covariance[4] = msg.orientation_covariance[8] = 0.01;
  return msg;
}

/// IMU x axis along base y (IMU turned +90 deg about z).
Mounting yawed90()
{
  Mounting m;
  m.imu_to_base = Quaternion(Eigen::AngleAxisd(M_PI / 2.0, Vector3::UnitZ()));
  return m;
}

std::string writeYaml(const std::string& content)
{
  char name[] = "/tmp/pbc_params_XXXXXX";
  const int fd = mkstemp(name);
  close(fd);
  std::ofstream(name) << content;
  return name;
}

/// Reads `content` over fresh defaults into *params.
bool readYaml(const std::string& content, Parameters* params, std::string* why)
{
  *params = Parameters();
  const std::string path = writeYaml(content);
  const bool ok = readParameters(YamlParameterSource(path), params, why);
  std::remove(path.c_str());
  return ok;
}
}  // namespace

TEST(Conversions, ImuSampleInBaseFrame)
{
  const ImuSample s = toImuSample(levelImu(), yawed90());
  EXPECT_DOUBLE_EQ(s.t, 1000.5);
  EXPECT_NEAR(s.specific_force.x(), 0.0, 1e-12);
  EXPECT_NEAR(s.specific_force.y(), 1.0, 1e-12);
  EXPECT_NEAR(s.specific_force.z(), kStandardGravity, 1e-12);
  EXPECT_NEAR(s.angular_rate.y(), 0.1, 1e-12);
  ASSERT_TRUE(s.has_orientation);
  // The IMU is level, so the base is level too but turned -90 deg about z relative to the IMU.
  const Vector3 base_x_in_level = s.orientation * Vector3::UnitX();
  EXPECT_NEAR(base_x_in_level.y(), -1.0, 1e-12);
}

TEST(Conversions, NoOrientationAndNonFinitePassThrough)
{
  sensor_msgs::Imu msg = levelImu();
  msg.orientation_covariance[0] = -1.0;
  msg.linear_acceleration.y = std::numeric_limits<double>::quiet_NaN();
  const ImuSample s = toImuSample(msg, Mounting());
  EXPECT_FALSE(s.has_orientation);
  EXPECT_TRUE(std::isnan(s.specific_force.y())) << "the core must see the NaN to reject and count it";
}

TEST(Mounting, LookedUpAsTheNodeAndCompensateBagUseIt)
{
  RosOptions options;  // base_frame base_link
  tf2::BufferCore tf;
  MountingLookup lookup = lookupMounting(tf, "imu_link", options);
  EXPECT_EQ(lookup.source, MountingSource::kMissing);
  EXPECT_FALSE(lookup.why.empty());
  EXPECT_TRUE(lookup.mounting.imu_to_base.isApprox(Quaternion::Identity()));

  // base_link -> mast -> imu_link: 90 deg about z, then the identity.
  geometry_msgs::TransformStamped base_mast, mast_imu;
  base_mast.header.frame_id = "base_link";
  base_mast.child_frame_id = "mast";
  base_mast.transform.rotation.z = std::sin(M_PI / 4.0);
  base_mast.transform.rotation.w = std::cos(M_PI / 4.0);
  mast_imu.header.frame_id = "mast";
  mast_imu.child_frame_id = "imu_link";
  mast_imu.transform.rotation.w = 1.0;
  mast_imu.transform.translation.z = 12.0;  // lever arm: not used
  ASSERT_TRUE(tf.setTransform(base_mast, "test", true));
  ASSERT_TRUE(tf.setTransform(mast_imu, "test", true));
  lookup = lookupMounting(tf, "imu_link", options);
  ASSERT_EQ(lookup.source, MountingSource::kTransform) << lookup.why;
  EXPECT_TRUE(lookup.mounting.imu_to_base.isApprox(yawed90().imu_to_base, 1e-12));
  EXPECT_EQ(describeMounting(lookup.mounting), "rpy 0 0 1.571 rad");

  // No lookup: the IMU's frame is the base frame, or identity_mounting.
  EXPECT_EQ(lookupMounting(tf, "base_link", options).source, MountingSource::kNotNeeded);
  options.identity_mounting = true;
  lookup = lookupMounting(tf, "imu_link", options);
  EXPECT_EQ(lookup.source, MountingSource::kNotNeeded);
  EXPECT_TRUE(lookup.mounting.imu_to_base.isApprox(Quaternion::Identity()));
}

TEST(Conversions, OdometryCovariancesAndFrames)
{
  CompensatorOutput out;
  out.position_filtered = Vector3(1.0, 2.0, 3.0);
  out.velocity_filtered = Vector3(0.5, 0.0, 0.0);
  out.position_variance = Vector3(0.1, 0.2, 0.3);
  out.velocity_variance = Vector3(0.01, 0.01, 0.01);
  out.position_wave = Vector3(0.05, 0.0, 0.0);
  out.wave_position_variance = Vector3(0.001, 0.001, 0.001);
  out.orientation = Quaternion(Eigen::AngleAxisd(M_PI / 2.0, Vector3::UnitZ()));

  sensor_msgs::Imu imu = levelImu();
  imu.orientation_covariance = {};  // unknown
  const OdometryFrames frames{ "odom", "base_link" };
  const nav_msgs::Odometry filtered =
      toOdometry(out, OdometryKind::kFiltered, imu, Mounting(), frames, ros::Time(1000.5));
  EXPECT_EQ(filtered.header.frame_id, "odom");
  EXPECT_EQ(filtered.child_frame_id, "base_link");
  EXPECT_DOUBLE_EQ(filtered.pose.pose.position.y, 2.0);
  EXPECT_DOUBLE_EQ(filtered.pose.covariance[0], 0.1);
  EXPECT_DOUBLE_EQ(filtered.pose.covariance[7], 0.2);
  EXPECT_DOUBLE_EQ(filtered.pose.covariance[14], 0.3);
  for (int i = 3; i < 6; ++i)
  {
    EXPECT_DOUBLE_EQ(filtered.pose.covariance[i * 7], kUnknownCovariance);
  }
  // Twist in the base frame: base x points north (level y), the eastward velocity is -y.
  EXPECT_NEAR(filtered.twist.twist.linear.x, 0.0, 1e-12);
  EXPECT_NEAR(filtered.twist.twist.linear.y, -0.5, 1e-12);
  EXPECT_TRUE(allFinite(filtered));

  const nav_msgs::Odometry wave = toOdometry(out, OdometryKind::kWave, levelImu(), Mounting(), frames, ros::Time(1));
  EXPECT_DOUBLE_EQ(wave.pose.pose.position.x, 0.05);
  EXPECT_DOUBLE_EQ(wave.pose.covariance[0], 0.001);
  EXPECT_DOUBLE_EQ(wave.pose.covariance[21], 0.01) << "orientation covariance from the message";

  sensor_msgs::Imu absent = levelImu();
  absent.orientation_covariance[0] = -1.0;
  const nav_msgs::Odometry no_orientation =
      toOdometry(out, OdometryKind::kFiltered, absent, Mounting(), frames, ros::Time(1));
  for (int i = 0; i < 6; ++i)
  {
    EXPECT_GE(no_orientation.pose.covariance[i * 7], 0.0) << "-1 on the pose diagonal";
  }

  out.position_filtered.x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(allFinite(toOdometry(out, OdometryKind::kFiltered, imu, Mounting(), frames, ros::Time(1))));
}

TEST(Conversions, BiasState)
{
  CompensatorOutput out;
  out.calibrated = true;
  out.axes[0].constant_bias = 0.02;
  out.axes[0].locked = true;
  out.axes[0].frequency = 0.443;
  BiasState msg = toBiasState(out, Mode::kPaper, "odom", ros::Time(5));
  EXPECT_EQ(msg.mode, "paper");
  EXPECT_TRUE(msg.calibrated);
  EXPECT_DOUBLE_EQ(msg.constant_bias[0], 0.02);
  EXPECT_TRUE(msg.period_locked[0]);
  EXPECT_FALSE(msg.period_locked[1]);
  EXPECT_TRUE(allFinite(msg));
  msg.d_p[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(allFinite(msg));
}

TEST(Conversions, FrameFilter)
{
  FrameFilter learn;
  EXPECT_FALSE(learn.known());
  EXPECT_TRUE(learn.accept(""));
  learn.learn("");  // an empty frame_id is never required
  EXPECT_FALSE(learn.known());
  EXPECT_TRUE(learn.accept("imu_link"));
  learn.learn("imu_link");
  EXPECT_TRUE(learn.known());
  EXPECT_TRUE(learn.accept("imu_link"));
  EXPECT_FALSE(learn.accept("other"));
  EXPECT_FALSE(learn.accept(""));
  learn.learn("other");  // the first frame learnt stays
  EXPECT_EQ(learn.expected(), "imu_link");

  FrameFilter fixed("imu_a");
  EXPECT_FALSE(fixed.accept("imu_b"));
  EXPECT_TRUE(fixed.accept("imu_a"));
}

/// Every key of config/compensator.yaml with whether the comment block above it marks it
/// [reconfigure] (a block of comment lines covers the keys that follow it).
std::map<std::string, bool> yamlKeysAndMarks(const std::string& path)
{
  std::map<std::string, bool> keys;
  std::ifstream file(path);
  std::string line, block;
  bool after_key = true;
  while (std::getline(file, line))
  {
    if (line.rfind("#", 0) == 0)
    {
      block = after_key ? line : block + line;
      after_key = false;
    }
    else if (!line.empty())
    {
      keys[line.substr(0, line.find(':'))] = block.find("[reconfigure]") != std::string::npos;
      after_key = true;
    }
  }
  return keys;
}

template <class Config>
void expectDefaults(const ParameterTable<Config>& table, const Config& read, std::map<std::string, bool>* yaml_keys)
{
  for (const Parameter<Config>& p : table)
  {
    const auto it = yaml_keys->find(p.key);
    if (it == yaml_keys->end())
    {
      ADD_FAILURE() << "config/compensator.yaml lacks " << p.key;
      continue;
    }
    EXPECT_EQ(p.get(read), p.defaultValue()) << p.key << ": the file says " << toString(p.get(read))
                                             << ", the table's default is " << toString(p.defaultValue());
    EXPECT_EQ(it->second, p.reconfigurable()) << p.key << ": [reconfigure] mark in config/compensator.yaml";
    yaml_keys->erase(it);
  }
}

TEST(Parameters, ShippedFileHoldsEveryKeyWithItsDefault)
{
  const std::string path = PBC_SOURCE_DIR "/config/compensator.yaml";
  Parameters params;
  std::string why;
  ASSERT_TRUE(readParameters(YamlParameterSource(path), &params, &why)) << why;
  std::map<std::string, bool> keys = yamlKeysAndMarks(path);
  expectDefaults(compensatorParameters(), params.core, &keys);
  expectDefaults(rosOptionParameters(), params.ros, &keys);
  for (const auto& [key, mark] : keys)
    ADD_FAILURE() << "config/compensator.yaml: '" << key << "' is in no parameter table";
}

TEST(Parameters, ErrorsNameTheKey)
{
  Parameters params;
  std::string why;
  EXPECT_FALSE(readYaml("alpha_v_x: 0.4\nbeta_q_y: 1.0\n", &params, &why));
  EXPECT_NE(why.find("beta_q_y"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("harmonics: 1.5\n", &params, &why));
  EXPECT_NE(why.find("harmonics"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("publish_tf: maybe\n", &params, &why));
  EXPECT_NE(why.find("publish_tf"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("mode: fast\n", &params, &why));
  EXPECT_NE(why.find("mode = 'fast' is not one of default, paper"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("min_frequency: 5\n", &params, &why));
  EXPECT_NE(why.find("min_frequency = 5 must be below max_frequency = 2"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("max_frequency: 0.01\n", &params, &why));
  EXPECT_NE(why.find("max_frequency = 0.01 must be above min_frequency = 0.05"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("fft_hop: 0.001\n", &params, &why));
  EXPECT_NE(why.find("fft_hop = 0.001 is out of range [0.01, 3600]"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("path_max_length: 0\n", &params, &why));
  EXPECT_NE(why.find("path_max_length = 0"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("base_frame: \"\"\n", &params, &why));
  EXPECT_NE(why.find("base_frame must not be empty"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("alpha_p_z: 3.0\n", &params, &why));
  EXPECT_NE(why.find("alpha_p_z"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("path_rate: 0\n", &params, &why));
  EXPECT_NE(why.find("path_rate"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("odom_frame: base_link\n", &params, &why));
  EXPECT_NE(why.find("odom_frame"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("imu_thread_priority: 100\n", &params, &why));
  EXPECT_NE(why.find("imu_thread_priority = 100 is out of range [0, 99]"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("imu_thread: false\nimu_thread_priority: 20\n", &params, &why));
  EXPECT_NE(why.find("imu_thread_priority needs imu_thread: true"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("cpu_wakeup_latency: 1.5\n", &params, &why));
  EXPECT_NE(why.find("cpu_wakeup_latency = 1.5 is out of range [-1, 1]"), std::string::npos) << why;
  EXPECT_THROW(YamlParameterSource("/nonexistent/params.yaml"), std::runtime_error);
  EXPECT_THROW(readYaml("- a\n- b\n", &params, &why), std::runtime_error);

  Parameters ok;
  ASSERT_TRUE(readYaml("mode: paper\nharmonics: 3\nfft_window: 40\nimu_frame: imu_link\n", &ok, &why)) << why;
  EXPECT_EQ(ok.core.mode, Mode::kPaper);
  EXPECT_EQ(ok.core.harmonics, 3);
  EXPECT_DOUBLE_EQ(ok.core.fft_window, 40.0);
  EXPECT_EQ(ok.ros.imu_frame, "imu_link");
  ASSERT_TRUE(readYaml("imu_thread_priority: 20\n", &ok, &why)) << why;
  EXPECT_EQ(ok.ros.imu_thread_priority, 20);
  EXPECT_DOUBLE_EQ(ok.ros.cpu_wakeup_latency, -1.0);
  ASSERT_TRUE(readYaml("cpu_wakeup_latency: 0\n", &ok, &why)) << why;
  EXPECT_DOUBLE_EQ(ok.ros.cpu_wakeup_latency, 0.0);
}

namespace
{
/// The values of a reconfigure message by key.
std::map<std::string, ParameterValue> values(const dynamic_reconfigure::Config& message)
{
  std::map<std::string, ParameterValue> result;
  for (const auto& e : message.bools)
    result[e.name] = static_cast<bool>(e.value);
  for (const auto& e : message.ints)
    result[e.name] = static_cast<int>(e.value);
  for (const auto& e : message.doubles)
    result[e.name] = static_cast<double>(e.value);
  for (const auto& e : message.strs)
    result[e.name] = e.value;
  return result;
}

std::map<std::string, ParameterValue> values(const Tuning& tuning)
{
  dynamic_reconfigure::Config message;
  tuning.__toMessage__(message);
  return values(message);
}

std::string readFile(const std::string& path)
{
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}
}  // namespace

// cfg/Compensator.cfg is declared apart from the table (dynamic_reconfigure runs it before any
// C++ exists): what it compiled to must be the table, key by key.
TEST(Parameters, ReconfigureDeclarationsAreTheTable)
{
  const auto defaults = values(Tuning::__getDefault__()), minima = values(Tuning::__getMin__()),
             maxima = values(Tuning::__getMax__());
  std::size_t run_time = 0;
  for (const Parameter<CompensatorConfig>& p : compensatorParameters())
  {
    if (!p.reconfigurable())
    {
      EXPECT_EQ(defaults.count(p.key), 0u) << p.key << " is in cfg/Compensator.cfg but not a run-time parameter";
      continue;
    }
    ++run_time;
    const std::string hint = std::string("; refresh: ") + kRefreshCommand;
    ASSERT_EQ(defaults.count(p.key), 1u) << p.key << " is missing from cfg/Compensator.cfg" << hint;
    EXPECT_EQ(defaults.at(p.key), p.defaultValue()) << p.key << ": default" << hint;
    if (p.type == ParameterType::kInt || p.type == ParameterType::kDouble)
    {
      const auto number = [](const ParameterValue& v) {
        return typeOf(v) == ParameterType::kInt ? std::get<int>(v) : std::get<double>(v);
      };
      // int bounds: dynamic_reconfigure's defaults (INT_MIN, INT_MAX) stand for none.
      const double none =
          p.type == ParameterType::kInt ? std::numeric_limits<int>::max() : std::numeric_limits<double>::infinity();
      const double lowest = std::isinf(p.range.lowest()) ? -none : p.range.lowest();
      const double highest = std::isinf(p.range.highest()) ? none : p.range.highest();
      EXPECT_EQ(number(minima.at(p.key)), lowest) << p.key << ": min" << hint;
      EXPECT_EQ(number(maxima.at(p.key)), highest) << p.key << ": max" << hint;
    }
    for (const auto& description : Tuning::__getParamDescriptions__())
      if (description->name == p.key)
      {
        EXPECT_EQ(description->type, reconfigureType(p.type)) << p.key << hint;
        EXPECT_EQ(description->description, reconfigureDescription(p)) << p.key << hint;
      }
  }
  EXPECT_EQ(defaults.size(), run_time) << "cfg/Compensator.cfg declares a key that is in no table";
  // The maximum a client is clamped to is one validate() accepts: alpha < 2.
  EXPECT_LT(Tuning::__getMax__().alpha_v_x, 2.0);
  CompensatorConfig at_max;
  at_max.gains[0].alpha_v = Tuning::__getMax__().alpha_v_x;
  std::string why;
  EXPECT_TRUE(at_max.validate(&why)) << why;
}

TEST(Parameters, ReconfigureRoundTrip)
{
  CompensatorConfig config;
  config.mode = Mode::kPaper;
  config.gains[2].beta_v = 7.25;
  config.harmonics = 3;
  config.heave_filter = false;
  config.gravity = 9.81;  // start-up only: not in a reconfigure message
  dynamic_reconfigure::Config message;
  Tuning::__getDefault__().__toMessage__(message);
  toTuning(config, &message);
  CompensatorConfig back;
  std::string why;
  ASSERT_TRUE(applyTuning(message, &back, &why)) << why;
  EXPECT_EQ(back.mode, Mode::kPaper);
  EXPECT_EQ(back.gains[2].beta_v, 7.25);
  EXPECT_EQ(back.harmonics, 3);
  EXPECT_FALSE(back.heave_filter);
  EXPECT_EQ(back.gravity, CompensatorConfig().gravity);
  for (const auto& change : changes(compensatorParameters(), config, back))
    EXPECT_EQ(change.info->key, "gravity") << "lost on the way: " << change.info->key;
  // The generated class reads the message back.
  Tuning tuning;
  ASSERT_TRUE(tuning.__fromMessage__(message));
  EXPECT_EQ(tuning.mode, "paper");
  EXPECT_EQ(tuning.beta_v_z, 7.25);

  dynamic_reconfigure::StrParameter mode;
  mode.name = "mode";
  mode.value = "fast";
  message.strs = { mode };
  EXPECT_FALSE(applyTuning(message, &back, &why));
  EXPECT_NE(why.find("mode = 'fast'"), std::string::npos) << why;
  dynamic_reconfigure::DoubleParameter gravity;
  gravity.name = "gravity";
  gravity.value = 9.8;
  message = dynamic_reconfigure::Config();
  message.doubles = { gravity };
  EXPECT_FALSE(applyTuning(message, &back, &why));
  EXPECT_NE(why.find("'gravity' is not a run-time parameter"), std::string::npos) << why;
}

// docs/ros_api.md and cfg/Compensator.cfg hold text generated from the tables.
TEST(Parameters, GeneratedTextIsCurrent)
{
  for (const GeneratedSection& section : generatedSections())
  {
    const std::string path = std::string(PBC_SOURCE_DIR) + "/" + section.file;
    std::string generated;
    ASSERT_TRUE(extractSection(readFile(path), section, &generated))
        << path << " lacks the marker lines '" << section.begin_marker << "' / '" << section.end_marker << "'";
    const std::string expected = section.generate();
    if (generated == expected)
    {
      continue;
    }
    std::istringstream have(generated), want(expected);
    std::string have_line, want_line;
    int line = 0;
    while (std::getline(have, have_line) && std::getline(want, want_line) && have_line == want_line)
    {
      ++line;
    }
    ADD_FAILURE() << section.file << " is not what the parameter tables give (line " << line + 1
                  << " of the generated part:\n  file:   " << have_line << "\n  tables: " << want_line
                  << ")\nrefresh it with\n  " << kRefreshCommand << "\n(<repository>: " << PBC_SOURCE_DIR << ")";
  }
  // The section replacement leaves the rest of a file alone.
  const GeneratedSection& docs = generatedSections().front();
  std::string updated;
  ASSERT_TRUE(replaceSection("intro\n" + docs.begin_marker + "\nold\n" + docs.end_marker + "\nrest\n", docs, &updated));
  EXPECT_EQ(updated, "intro\n" + docs.begin_marker + "\n" + docs.generate() + docs.end_marker + "\nrest\n");
  EXPECT_FALSE(replaceSection("no markers\n", docs, &updated));
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
