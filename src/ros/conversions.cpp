#include "periodic_bias_compensation/ros/conversions.h"

#include <cmath>

#include <Eigen/Core>

namespace periodic_bias_compensation
{
namespace
{
using Matrix3 = Eigen::Matrix3d;

Vector3 toVector(const geometry_msgs::Vector3& v)
{
  return Vector3(v.x, v.y, v.z);
}

void fromVector(const Vector3& v, geometry_msgs::Vector3* out)
{
  out->x = v.x();
  out->y = v.y();
  out->z = v.z();
}

/// Row-major 3x3 covariance of an Imu message; false when marked unknown (all zeros) or absent (-1).
bool messageCovariance(const boost::array<double, 9>& cov, Matrix3* out)
{
  if (cov[0] == -1.0)
  {
    return false;
  }
  bool any_nonzero = false;
  for (double c : cov)
  {
    if (!std::isfinite(c))
    {
      return false;
    }
    any_nonzero = any_nonzero || c != 0.0;
  }
  if (!any_nonzero)
  {
    return false;
  }
  *out = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cov.data());
  return true;
}

/// Writes a 3x3 block into a row-major 6x6 covariance at (offset, offset).
void setBlock(const Matrix3& block, int offset, boost::array<double, 36>* cov)
{
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      (*cov)[(offset + r) * 6 + offset + c] = block(r, c);
    }
  }
}

bool finite(const geometry_msgs::Vector3& v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

template <std::size_t N>
bool finite(const boost::array<double, N>& values)
{
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      return false;
    }
  }
  return true;
}
}  // namespace

ImuSample toImuSample(const sensor_msgs::Imu& msg, const Mounting& mounting)
{
  ImuSample sample;
  sample.t = msg.header.stamp.toSec();
  const Matrix3 r_base_imu = mounting.imu_to_base.toRotationMatrix();
  sample.specific_force.noalias() = r_base_imu * toVector(msg.linear_acceleration);
  sample.angular_rate.noalias() = r_base_imu * toVector(msg.angular_velocity);
  sample.has_orientation = msg.orientation_covariance[0] != -1.0;
  if (sample.has_orientation)
  {
    // Not normalised here: the core rejects zero and non-unit quaternions and counts them.
    const Quaternion level_from_imu(msg.orientation.w, msg.orientation.x, msg.orientation.y, msg.orientation.z);
    sample.orientation = level_from_imu * mounting.imu_to_base.conjugate();
  }
  return sample;
}

bool plausible(const ImuSample& sample)
{
  for (int i = 0; i < 3; ++i)
  {
    // Written so that NaN passes (comparisons with NaN are false).
    if (std::abs(sample.specific_force[i]) > kMaxSpecificForce || std::abs(sample.angular_rate[i]) > kMaxAngularRate)
    {
      return !(std::isfinite(sample.specific_force[i]) && std::isfinite(sample.angular_rate[i]));
    }
  }
  return true;
}

nav_msgs::Odometry toOdometry(const CompensatorOutput& out, OdometryKind kind, const sensor_msgs::Imu& imu,
                              const Mounting& mounting, const OdometryFrames& frames, const ros::Time& stamp)
{
  const bool wave = kind == OdometryKind::kWave;
  const Vector3& position = wave ? out.position_wave : out.position_filtered;
  const Vector3& velocity_level = wave ? out.velocity_wave : out.velocity_filtered;
  const Vector3& position_variance = wave ? out.wave_position_variance : out.position_variance;

  nav_msgs::Odometry msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frames.odom_frame;
  msg.child_frame_id = frames.base_frame;

  msg.pose.pose.position.x = position.x();
  msg.pose.pose.position.y = position.y();
  msg.pose.pose.position.z = position.z();
  const Quaternion q = out.orientation.normalized();
  msg.pose.pose.orientation.w = q.w();
  msg.pose.pose.orientation.x = q.x();
  msg.pose.pose.orientation.y = q.y();
  msg.pose.pose.orientation.z = q.z();

  const Matrix3 r_base_imu = mounting.imu_to_base.toRotationMatrix();
  const Matrix3 r_level_base = q.toRotationMatrix();
  const Matrix3 unknown = Matrix3::Identity() * kUnknownCovariance;

  Matrix3 orientation_cov;
  if (messageCovariance(imu.orientation_covariance, &orientation_cov))
  {
    orientation_cov = r_base_imu * orientation_cov * r_base_imu.transpose();
  }
  else
  {
    orientation_cov = unknown;
  }
  setBlock(position_variance.asDiagonal(), 0, &msg.pose.covariance);
  setBlock(orientation_cov, 3, &msg.pose.covariance);

  // Twist is expressed in child_frame_id (base frame).
  const Matrix3 r_base_level = r_level_base.transpose();
  fromVector(r_base_level * velocity_level, &msg.twist.twist.linear);
  fromVector(r_base_imu * toVector(imu.angular_velocity), &msg.twist.twist.angular);
  const Vector3& velocity_variance = wave ? out.wave_velocity_variance : out.velocity_variance;
  Matrix3 rate_cov;
  if (messageCovariance(imu.angular_velocity_covariance, &rate_cov))
  {
    rate_cov = r_base_imu * rate_cov * r_base_imu.transpose();
  }
  else
  {
    rate_cov = unknown;
  }
  setBlock(r_base_level * velocity_variance.asDiagonal() * r_base_level.transpose(), 0, &msg.twist.covariance);
  setBlock(rate_cov, 3, &msg.twist.covariance);
  return msg;
}

BiasState toBiasState(const CompensatorOutput& out, Mode mode, const std::string& odom_frame, const ros::Time& stamp)
{
  BiasState msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = odom_frame;
  msg.mode = toString(mode);
  msg.calibrated = out.calibrated;
  msg.state = out.state == OutputState::kCalibrating ? BiasState::STATE_CALIBRATING : BiasState::STATE_TRACKING;
  for (std::size_t i = 0; i < 3; ++i)
  {
    const AxisState& axis = out.axes[i];
    msg.constant_bias[i] = axis.constant_bias;
    msg.periodic_bias[i] = axis.periodic_bias;
    msg.dominant_frequency[i] = axis.frequency;
    msg.period_samples[i] = axis.period_samples;
    msg.period_locked[i] = axis.locked;
    msg.d_v[i] = axis.d_v;
    msg.d_p[i] = axis.d_p;
  }
  return msg;
}

bool allFinite(const nav_msgs::Odometry& msg)
{
  const auto& p = msg.pose.pose;
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
         std::isfinite(p.orientation.w) && std::isfinite(p.orientation.x) && std::isfinite(p.orientation.y) &&
         std::isfinite(p.orientation.z) && finite(msg.twist.twist.linear) && finite(msg.twist.twist.angular) &&
         finite(msg.pose.covariance) && finite(msg.twist.covariance);
}

bool allFinite(const BiasState& msg)
{
  return finite(msg.constant_bias) && finite(msg.periodic_bias) && finite(msg.dominant_frequency) &&
         finite(msg.period_samples) && finite(msg.d_v) && finite(msg.d_p);
}

bool FrameFilter::accept(const std::string& frame_id) const
{
  return !fixed_ || frame_id == expected_;
}

void FrameFilter::learn(const std::string& frame_id)
{
  if (fixed_ || frame_id.empty())
    return;
  expected_ = frame_id;
  fixed_ = true;
}

}  // namespace periodic_bias_compensation
