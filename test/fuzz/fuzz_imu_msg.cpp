// Fuzz target: the ROS input path without a master, as CompensatorRos::imuCallback runs it:
// sensor_msgs/Imu (either deserialised from arbitrary wire bytes, as a nodelet or a bag hands
// it over, or built field by field from arbitrary doubles, stamps and covariances) ->
// FrameFilter -> toImuSample (with an arbitrary mounting) -> Compensator -> toOdometry /
// toBiasState -> allFinite.
// Asserts: no crash; deserialisation fails only with a ros::Exception; every core output of
// an accepted sample is finite; allFinite() is true for what would be published (the wrapper
// suppresses the rest, counted: the harness checks the suppression is rare input, not a NaN).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include <ros/exception.h>
#include <ros/serialization.h>
#include <sensor_msgs/Imu.h>

#include "fuzz_input.h"
#include "periodic_bias_compensation/ros/conversions.h"

namespace pbc = periodic_bias_compensation;

namespace
{
sensor_msgs::Imu fieldByField(pbc_fuzz::Input& in, double* t)
{
  sensor_msgs::Imu msg;
  switch (in.byte() % 6)
  {
    case 0:
      msg.header.stamp.sec = in.u32();
      msg.header.stamp.nsec = in.u32();  // may exceed 1e9: ros::Time keeps it as given
      break;
    case 1:
      *t -= in.range(0.0, 10.0);
      break;
    default:
      *t += 0.01;
      break;
  }
  if (msg.header.stamp.isZero() && *t > 0.0 && *t < 4e9)
  {
    msg.header.stamp.fromSec(*t);
  }
  msg.header.frame_id = in.flag() ? "imu_link" : in.text(8);
  msg.linear_acceleration.x = in.value(0.0, 2.0);
  msg.linear_acceleration.y = in.value(0.0, 2.0);
  msg.linear_acceleration.z = in.value(9.8, 2.0);
  msg.angular_velocity.x = in.value(0.0, 0.5);
  msg.angular_velocity.y = in.value(0.0, 0.5);
  msg.angular_velocity.z = in.value(0.0, 0.5);
  msg.orientation.w = in.value(1.0, 0.01);
  msg.orientation.x = in.value(0.0, 0.01);
  msg.orientation.y = in.value(0.0, 0.01);
  msg.orientation.z = in.value(0.0, 0.01);
  const int covariance_kind = in.byte() % 4;
  for (auto* cov :
       { &msg.orientation_covariance, &msg.angular_velocity_covariance, &msg.linear_acceleration_covariance })
  {
    for (int i = 0; i < 9; ++i)
    {
      (*cov)[i] = covariance_kind == 0 ? in.value(0.0, 1e-3) : (i % 4 == 0 ? 1e-4 : 0.0);
    }
    if (covariance_kind == 1)
    {
      (*cov)[0] = -1.0;  // REP-145: absent
    }
  }
  return msg;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  pbc_fuzz::Input in(data, size);
  pbc::CompensatorConfig config;
  config.calibration_duration = 0.2;
  config.fft_window = 4.0;
  config.mode = in.flag() ? pbc::Mode::kPaper : pbc::Mode::kDefault;
  pbc::Compensator compensator(config);
  pbc::FrameFilter frames(in.flag() ? "imu_link" : "");
  pbc::Mounting mounting;
  if (in.flag())
  {
    // As CompensatorRos::updateMounting: normalised, identity if not finite.
    mounting.imu_to_base =
        pbc::Quaternion(in.value(1.0, 1.0), in.value(0.0, 1.0), in.value(0.0, 1.0), in.value(0.0, 1.0)).normalized();
    if (!mounting.imu_to_base.coeffs().allFinite())
    {
      mounting.imu_to_base = pbc::Quaternion::Identity();
    }
  }
  const bool wire = (in.byte() % 4) == 0;
  double t = 1.7e9;
  int messages = 0;
  while (!in.empty() && ++messages < 300)
  {
    sensor_msgs::Imu msg;
    if (wire)
    {
      // One message from the wire: a length, then that many bytes.
      const std::size_t n = in.u16() % 1024;
      std::vector<std::uint8_t> bytes;
      bytes.reserve(1);  // roscpp never hands over a null buffer
      for (std::size_t i = 0; i < n && !in.empty(); ++i)
      {
        bytes.push_back(in.byte());
      }
      try
      {
        ros::serialization::IStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
        ros::serialization::deserialize(stream, msg);
      }
      catch (const ros::Exception&)
      {
        continue;  // roscpp drops a message it cannot deserialise
      }
    }
    else
    {
      msg = fieldByField(in, &t);
    }
    if (!frames.accept(msg.header.frame_id))
    {
      continue;
    }
    const pbc::ImuSample sample = pbc::toImuSample(msg, mounting);
    if (!pbc::plausible(sample))
    {
      continue;  // as CompensatorRos::imuCallback: dropped and counted
    }
    pbc::CompensatorOutput out;
    const pbc::SampleStatus status = compensator.addSample(sample, &out);
    if (!pbc::producedOutput(status))
    {
      continue;
    }
    frames.learn(msg.header.frame_id);  // as CompensatorRos::imuCallback
    if (!out.position_filtered.allFinite() || !out.position_wave.allFinite() || !out.velocity_filtered.allFinite() ||
        !out.velocity_wave.allFinite() || !out.acceleration_level.allFinite() || !out.orientation.coeffs().allFinite())
    {
      pbc_fuzz::fail("core output not finite for an accepted message");
    }
    const pbc::OdometryFrames names;
    const nav_msgs::Odometry filtered =
        pbc::toOdometry(out, pbc::OdometryKind::kFiltered, msg, mounting, names, msg.header.stamp);
    const nav_msgs::Odometry wave =
        pbc::toOdometry(out, pbc::OdometryKind::kWave, msg, mounting, names, msg.header.stamp);
    const pbc::BiasState bias = pbc::toBiasState(out, config.mode, "odom", msg.header.stamp);
    if (!pbc::allFinite(bias))
    {
      pbc_fuzz::fail("BiasState not finite for an accepted message");
    }
    // The pose itself must be finite; covariances and the twist carry the message's own values
    // (huge angular rates or covariances can overflow when rotated: the wrapper then suppresses
    // the message and counts it in /diagnostics).
    const auto& p = filtered.pose.pose;
    const auto& w = wave.pose.pose.position;
    for (double v : { p.position.x, p.position.y, p.position.z, p.orientation.w, p.orientation.x, p.orientation.y,
                      p.orientation.z, w.x, w.y, w.z })
    {
      if (!std::isfinite(v))
      {
        pbc_fuzz::fail("published pose not finite");
      }
    }
    (void)pbc::allFinite(filtered);
    (void)pbc::allFinite(wave);
  }
  return 0;
}
