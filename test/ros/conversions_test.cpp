// Wrapper pieces without a master: Imu -> ImuSample with a mounting rotation, the mounting
// looked up in a tf2 buffer (node and compensate_bag), Odometry covariances (never -1, unknown ->
// kUnknownCovariance), finite checks, the frame filter, the parameter table read from YAML (unknown key, wrong type, invalid value named), and the raw
// double integration.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "periodic_bias_compensation/ros/conversions.h"
#include "periodic_bias_compensation/ros/mounting.h"
#include "periodic_bias_compensation/ros/parameters.h"
#include "periodic_bias_compensation/ros/raw_integrator.h"

using namespace periodic_bias_compensation;

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

TEST(Parameters, ShippedFileReadsAndKeepsTheCoreDefaults)
{
  Parameters params;
  std::string why;
  ASSERT_TRUE(readParameters(YamlParameterSource(PBC_SOURCE_DIR "/config/compensator.yaml"), &params, &why)) << why;
  // config/compensator.yaml documents the defaults: it must agree with the core's.
  const CompensatorConfig defaults;
  const CompensatorConfig& c = params.core;
  EXPECT_EQ(c.mode, defaults.mode);
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_DOUBLE_EQ(c.gains[i].alpha_v, defaults.gains[i].alpha_v);
    EXPECT_DOUBLE_EQ(c.gains[i].alpha_p, defaults.gains[i].alpha_p);
    EXPECT_DOUBLE_EQ(c.gains[i].beta_v, defaults.gains[i].beta_v);
    EXPECT_DOUBLE_EQ(c.gains[i].beta_p, defaults.gains[i].beta_p);
  }
  EXPECT_EQ(c.enable_constant, defaults.enable_constant);
  EXPECT_EQ(c.enable_periodic, defaults.enable_periodic);
  EXPECT_DOUBLE_EQ(c.calibration_duration, defaults.calibration_duration);
  EXPECT_EQ(c.assume_static_calibration, defaults.assume_static_calibration);
  EXPECT_DOUBLE_EQ(c.fft_window, defaults.fft_window);
  EXPECT_DOUBLE_EQ(c.fft_hop, defaults.fft_hop);
  EXPECT_DOUBLE_EQ(c.min_frequency, defaults.min_frequency);
  EXPECT_DOUBLE_EQ(c.max_frequency, defaults.max_frequency);
  EXPECT_DOUBLE_EQ(c.min_peak_ratio, defaults.min_peak_ratio);
  EXPECT_EQ(c.harmonics, defaults.harmonics);
  EXPECT_DOUBLE_EQ(c.harmonic_memory, defaults.harmonic_memory);
  EXPECT_DOUBLE_EQ(c.drift_time_constant, defaults.drift_time_constant);
  EXPECT_EQ(c.gyro_attitude, defaults.gyro_attitude);
  EXPECT_DOUBLE_EQ(c.tilt_time_constant, defaults.tilt_time_constant);
  EXPECT_EQ(c.estimate_gyro_bias, defaults.estimate_gyro_bias);
  EXPECT_DOUBLE_EQ(c.gravity, defaults.gravity);
  EXPECT_DOUBLE_EQ(c.max_gap, defaults.max_gap);
  EXPECT_DOUBLE_EQ(c.max_rate_change, defaults.max_rate_change);
  EXPECT_DOUBLE_EQ(c.max_quaternion_norm_error, defaults.max_quaternion_norm_error);
  const RosOptions ros_defaults;
  EXPECT_EQ(params.ros.odom_frame, ros_defaults.odom_frame);
  EXPECT_EQ(params.ros.base_frame, ros_defaults.base_frame);
  EXPECT_EQ(params.ros.path_max_length, ros_defaults.path_max_length);
  EXPECT_DOUBLE_EQ(params.ros.path_rate, ros_defaults.path_rate);
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
  EXPECT_NE(why.find("mode"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("alpha_p_z: 3.0\n", &params, &why));
  EXPECT_NE(why.find("alpha_p_z"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("path_rate: 0\n", &params, &why));
  EXPECT_NE(why.find("path_rate"), std::string::npos) << why;
  EXPECT_FALSE(readYaml("odom_frame: base_link\n", &params, &why));
  EXPECT_NE(why.find("odom_frame"), std::string::npos) << why;
  EXPECT_THROW(YamlParameterSource("/nonexistent/params.yaml"), std::runtime_error);
  EXPECT_THROW(readYaml("- a\n- b\n", &params, &why), std::runtime_error);

  Parameters ok;
  ASSERT_TRUE(readYaml("mode: paper\nharmonics: 3\nfft_window: 40\nimu_frame: imu_link\n", &ok, &why)) << why;
  EXPECT_EQ(ok.core.mode, Mode::kPaper);
  EXPECT_EQ(ok.core.harmonics, 3);
  EXPECT_DOUBLE_EQ(ok.core.fft_window, 40.0);
  EXPECT_EQ(ok.ros.imu_frame, "imu_link");
}

TEST(RawIntegrator, ConstantAccelerationAndRestarts)
{
  RawIntegrator raw;
  const Vector3 a(0.2, 0.0, 0.0);
  for (int i = 0; i <= 100; ++i)
  {
    raw.add(0.01 * i, a, false);
  }
  EXPECT_NEAR(raw.position().x(), 0.5 * 0.2 * 1.0 * 1.0, 1e-9);
  const double before_gap = raw.position().x();
  raw.add(5.0, a, true);  // after a gap: no integration across it
  EXPECT_DOUBLE_EQ(raw.position().x(), before_gap);
  raw.reset();
  EXPECT_DOUBLE_EQ(raw.position().norm(), 0.0);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
