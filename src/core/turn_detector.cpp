#include "periodic_bias_compensation/core/turn_detector.h"

#include <algorithm>
#include <cmath>

#include "periodic_bias_compensation/common/numeric.h"

namespace periodic_bias_compensation
{
double headingOf(const Eigen::Quaterniond& orientation)
{
  return headingOf(orientation.toRotationMatrix());
}

double headingOf(const Eigen::Matrix3d& rotation)
{
  return std::atan2(rotation(1, 0), rotation(0, 0));
}

void TurnDetector::reset()
{
  *this = TurnDetector();
}

void TurnDetector::update(double heading, double yaw_rate, double dt, bool attitude_measured)
{
  followHeading(heading, dt);
  followYawRate(yaw_rate, dt);
  attitude_measured_ = attitude_measured;
  if (!attitude_measured)
    since_turn_ = 0.0;
}

void TurnDetector::followHeading(double heading, double dt)
{
  turned_ = false;
  if (heading_samples_++ == 0)
  {
    heading_ = heading_mean_ = record_heading_ = heading;
    return;
  }
  heading_ += wrapAngle(heading - heading_);
  const double weight =
      std::max(dt > 0.0 ? 1.0 - std::exp(-dt / kHeadingAveraging) : 0.0, 1.0 / static_cast<double>(heading_samples_));
  heading_mean_ += weight * (heading_ - heading_mean_);
  if (std::abs(heading_mean_ - record_heading_) > kRecordTurn)
  {
    turned_ = true;
    record_heading_ = heading_mean_;
  }
}

void TurnDetector::followYawRate(double yaw_rate, double dt)
{
  const auto weight = [dt](double time_constant) { return dt > 0.0 ? std::min(1.0, dt / time_constant) : 0.0; };
  turn_rate_ += weight(kTurnAveraging) * (yaw_rate - turn_rate_);
  sustained_turn_rate_ += weight(kSustainedTurnAveraging) * (yaw_rate - sustained_turn_rate_);
  const double deviation = turn_rate_ - sustained_turn_rate_;
  yaw_samples_ += 1.0;
  yaw_spread_ += std::max(weight(kYawSpreadAveraging), 1.0 / yaw_samples_) * (deviation * deviation - yaw_spread_);
  const double threshold = std::max(kTurnRate, kYawSpreads * std::sqrt(yaw_spread_));
  const bool yawing = std::abs(turn_rate_) > threshold || turned_;
  since_turn_ = yawing ? 0.0 : since_turn_ + dt;
  since_yaw_ = yawing ? 0.0 : since_yaw_ + dt;
  if (turned_)
    turn_confirmed_ = true;
  else if (since_turn_ >= kAfterTurn)
    turn_confirmed_ = false;
}
}  // namespace periodic_bias_compensation
