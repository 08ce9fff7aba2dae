#include "periodic_bias_compensation/core/calibration_window.h"

#include <algorithm>

#include "periodic_bias_compensation/core/harmonic_model.h"

namespace periodic_bias_compensation
{
double windowOffset(const std::vector<double>& values, const WindowOffsetOptions& options, FrequencyEstimate* frequency)
{
  double mean = 0.0;
  for (double v : values)
    mean += v;
  mean /= values.size();
  if (options.at_rest || values.size() < 16)
    return mean;
  FrequencyTracker tracker(static_cast<int>(values.size()), options.rate);
  for (double v : values)
    tracker.push(v - mean);
  *frequency = tracker.analyse(options.min_frequency, std::min(options.max_frequency, 0.45 * options.rate),
                               options.min_peak_ratio);
  if (!frequency->locked)
    return mean;
  return harmonicConstant(values, options.rate, frequency->frequency, options.harmonics);
}

bool CalibrationWindow::add(const ImuSample& sample, double dt, double duration)
{
  samples_.push_back({ sample, dt });
  force_sum_ += sample.specific_force;
  any_without_orientation_ |= !sample.has_orientation;
  if (samples_.size() == 1)
    start_ = sample.t;
  return sample.t - start_ >= duration;
}

void CalibrationWindow::noteLevel(const Vector3& level_acceleration)
{
  // Only in step with the samples, each of them with its orientation.
  if (any_without_orientation_ || level_axes_[0].size() + 1 != samples_.size())
    return;
  for (int i = 0; i < 3; ++i)
    level_axes_[i].push_back(level_acceleration[i]);
}

Vector3 CalibrationWindow::provisionalBias(const Vector3& level_acceleration)
{
  provisional_sum_ = samples_.size() <= 1 ? level_acceleration : provisional_sum_ + level_acceleration;
  return provisional_sum_ / static_cast<double>(std::max<std::size_t>(1, samples_.size()));
}

Vector3 CalibrationWindow::meanSpecificForce(bool* any_without_orientation) const
{
  *any_without_orientation = any_without_orientation_;
  return force_sum_ / static_cast<double>(samples_.size());
}

std::array<std::vector<double>, 3> CalibrationWindow::levelAxes(const std::function<Vector3(const ImuSample&)>& level)
{
  std::array<std::vector<double>, 3> axes;
  const std::size_t noted = any_without_orientation_ ? 0 : std::min(level_axes_[0].size(), samples_.size());
  for (int i = 0; i < 3; ++i)
  {
    axes[i].swap(level_axes_[i]);
    axes[i].resize(noted);
    axes[i].reserve(samples_.size());
  }
  for (std::size_t k = noted; k < samples_.size(); ++k)
  {
    const Vector3 a = level(samples_[k].sample);
    for (int i = 0; i < 3; ++i)
      axes[i].push_back(a[i]);
  }
  return axes;
}

Vector3 CalibrationWindow::constantPositionDrift(const std::function<Vector3(const ImuSample&)>& level,
                                                 const Vector3& bias) const
{
  Vector3 v = Vector3::Zero(), sum = Vector3::Zero();
  for (const auto& b : samples_)
  {
    v += (level(b.sample) - bias) * b.dt;
    sum += v;
  }
  return sum / static_cast<double>(samples_.size());
}
}  // namespace periodic_bias_compensation
