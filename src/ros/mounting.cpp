#include "periodic_bias_compensation/ros/mounting.h"

#include <cmath>
#include <cstdio>

#include <geometry_msgs/TransformStamped.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2/exceptions.h>

namespace periodic_bias_compensation
{
MountingLookup lookupMounting(const tf2::BufferCore& tf, const std::string& imu_frame, const RosOptions& options)
{
  MountingLookup result;
  if (imu_frame == options.base_frame || options.identity_mounting)
  {
    result.source = MountingSource::kNotNeeded;
    return result;
  }
  try
  {
    // The latest transform: the mounting is taken as fixed.
    const geometry_msgs::TransformStamped transform = tf.lookupTransform(options.base_frame, imu_frame, ros::Time(0));
    const auto& r = transform.transform.rotation;
    const Quaternion rotation(r.w, r.x, r.y, r.z);
    if (!rotation.coeffs().allFinite() || rotation.norm() < 1e-6)
    {
      result.why = "transform " + imu_frame + " -> " + options.base_frame + " has an invalid rotation";
      return result;
    }
    result.mounting.imu_to_base = rotation.normalized();
    result.source = MountingSource::kTransform;
  }
  catch (const tf2::TransformException& e)
  {
    result.why = e.what();
  }
  return result;
}

std::string describeMounting(const Mounting& mounting)
{
  const Quaternion& q = mounting.imu_to_base;
  double rpy[3];
  tf2::Matrix3x3(tf2::Quaternion(q.x(), q.y(), q.z(), q.w())).getRPY(rpy[0], rpy[1], rpy[2]);
  for (double& angle : rpy)
  {
    angle = std::abs(angle) < 5e-5 ? 0.0 : angle;  // no "-0" or "1e-17" for a zero angle
  }
  char text[96];
  std::snprintf(text, sizeof text, "rpy %.4g %.4g %.4g rad", rpy[0], rpy[1], rpy[2]);
  return text;
}
}  // namespace periodic_bias_compensation
