#include "periodic_bias_compensation/ros/sim_messages.h"

namespace periodic_bias_compensation
{
namespace
{
geometry_msgs::Vector3 toVector(const sim::Vector3& v)
{
  geometry_msgs::Vector3 m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}

geometry_msgs::Quaternion toQuaternion(const sim::Quaternion& q)
{
  geometry_msgs::Quaternion m;
  m.w = q.w();
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  return m;
}

void fillOdometry(const ros::Time& stamp, const sim::OdometryState& state, nav_msgs::Odometry* m)
{
  m->header.stamp = stamp;
  m->header.frame_id = "odom";
  m->child_frame_id = "base_link";
  m->pose.pose.position.x = state.position.x();
  m->pose.pose.position.y = state.position.y();
  m->pose.pose.position.z = state.position.z();
  m->pose.pose.orientation = toQuaternion(state.orientation);
  m->twist.twist.linear = toVector(state.linear_velocity);
  m->twist.twist.angular = toVector(state.angular_velocity);
}
}  // namespace

SimMessageBuilder::SimMessageBuilder(const sim::Scenario& scenario)
{
  const sim::ImuCovariance cov = sim::imuCovariance(scenario);
  imu_template_.header.frame_id = "imu_link";
  for (int i = 0; i < 3; ++i)
  {
    imu_template_.orientation_covariance[4 * i] = cov.orientation_variance;
    imu_template_.angular_velocity_covariance[4 * i] = cov.gyro_variance[i];
    imu_template_.linear_acceleration_covariance[4 * i] = cov.accel_variance[i];
  }
}

void SimMessageBuilder::build(const sim::Sample& s, SimMessages* out) const
{
  out->has_imu = !s.dropped;
  out->has_temperature = out->has_imu && s.has_temperature;
  if (out->has_imu)
  {
    out->imu = imu_template_;
    out->imu.header.stamp = ros::Time(s.stamp);
    out->imu.header.seq = static_cast<std::uint32_t>(s.index);
    out->imu.orientation = toQuaternion(s.orientation);
    out->imu.angular_velocity = toVector(s.gyro);
    out->imu.linear_acceleration = toVector(s.accel);
  }
  if (out->has_temperature)
  {
    out->temperature.header = out->imu.header;
    out->temperature.temperature = s.temperature;
  }
  const ros::Time t(s.t);
  const sim::TruthOdometry odom = sim::truthOdometry(s.truth);
  fillOdometry(t, odom.total, &out->truth);
  fillOdometry(t, odom.slow, &out->truth_slow);
  fillOdometry(t, odom.wave, &out->truth_wave);
}
}  // namespace periodic_bias_compensation
