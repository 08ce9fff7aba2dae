#include "periodic_bias_compensation/core/leveller.h"

#include <algorithm>
#include <cmath>

namespace periodic_bias_compensation
{
// Whether the last sample had orientation, and the last level frame, are kept: the next sample
// is judged by the last one until it has been levelled itself.
void Leveller::reset()
{
  gyro_.reset();
  gyro_levelled_ = false;
  has_level_ = false;
  calibrated_ = false;
  source_ = LevelSource::kNone;
  attitude_samples_ = 0;
  orientation_lost_ = false;
}

void Leveller::orient(ImuSample* s, double dt, bool use_gyro, const GyroAttitudeConfig& gyro)
{
  gyro_levelled_ = false;
  if (use_gyro)
  {
    if (s->has_orientation)
    {
      gyro_.reset(s->orientation);
    }
    else
    {
      gyro_.setConfig(gyro);
      gyro_.update(s->angular_rate, s->specific_force, dt);
      if (gyro_.initialised())
      {
        s->orientation = gyro_.attitude();
        s->has_orientation = true;
        gyro_levelled_ = true;
      }
    }
  }
  updateLevel(*s, dt);
}

// While the IMU gives orientation its mean over kAttitudeMemory is kept; when it stops, that mean
// is used (the hull's roll and pitch at one instant would tilt the frame by the wave motion).
void Leveller::updateLevel(const ImuSample& s, double dt)
{
  if (s.has_orientation)
  {
    // Running mean of unit quaternions (close together: the normalised component mean), a plain
    // mean for the first samples, then exponential forgetting.
    Quaternion q = s.orientation;
    if (attitude_samples_ > 0 && q.coeffs().dot(attitude_.coeffs()) < 0.0)
      q.coeffs() *= -1.0;
    ++attitude_samples_;
    const double weight = std::max(1.0 - std::exp(-dt / kAttitudeMemory), 1.0 / attitude_samples_);
    attitude_.coeffs() =
        attitude_samples_ == 1 ? q.coeffs() : (attitude_.coeffs() + weight * (q.coeffs() - attitude_.coeffs())).eval();
    attitude_.normalize();
    orientation_lost_ = false;
    return;
  }
  if (attitude_samples_ > 0 && !orientation_lost_)
  {
    level_ = attitude_;
    has_level_ = true;
    source_ = LevelSource::kAttitudeBeforeLoss;
  }
  else if (!has_level_)
  {
    level_ = levelFromSpecificForce(s.specific_force);
    has_level_ = true;
    source_ = LevelSource::kGravity;
  }
  orientation_lost_ = true;
}

Vector3 Leveller::levelAcceleration(const ImuSample& s, double gravity)
{
  last_had_orientation_ = s.has_orientation;
  const Quaternion& q = s.has_orientation ? s.orientation : level_;
  return q * s.specific_force - Vector3(0.0, 0.0, gravity);
}

void Leveller::calibrate(const Vector3& mean_specific_force, bool any_without_orientation)
{
  if (any_without_orientation && source_ != LevelSource::kAttitudeBeforeLoss)
  {
    level_ = levelFromSpecificForce(mean_specific_force);
    source_ = LevelSource::kGravity;
  }
  calibrated_ = true;
}

}  // namespace periodic_bias_compensation
