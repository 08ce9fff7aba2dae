// The calibration window: the first calibration_duration of a record, from which the constant
// bias and the level frame come (estimation core, no ROS).
//
// The window keeps its samples; when it ends the owner takes the level frame from their mean
// specific force, the constant bias of each level axis from windowOffset(), and processes the
// samples again with them (causal: only past samples are used). Until then the bias is
// provisional: the running mean of the level acceleration so far.
//
// windowOffset() is the mean of the window when it is at rest (paper Sec. 3.1, and paper mode),
// else the constant of a harmonic fit at the window's dominant frequency, so that an oscillation
// over a non-whole number of periods does not bias it. constantPositionDrift() is the paper's
// "distance bias" (Table 1): after the constant bias is removed, the mean velocity over the
// window is a constant position drift per unit time.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/frequency_tracker.h"

namespace periodic_bias_compensation
{
/// How windowOffset() looks for the window's dominant frequency.
struct WindowOffsetOptions
{
  bool at_rest = false;                             ///< the window is known to be at rest: its mean
  double rate = 0.0;                                ///< sample rate [Hz]
  double min_frequency = 0.0, max_frequency = 0.0;  ///< band searched [Hz]
  double min_peak_ratio = 0.0;                      ///< peak / median power a lock needs [-]
  int harmonics = 1;                                ///< harmonics of the fit [-]
};

/// Offset of one axis over a window; *frequency: the dominant frequency found (not locked when
/// the mean was taken).
double windowOffset(const std::vector<double>& values, const WindowOffsetOptions& options,
                    FrequencyEstimate* frequency);

class CalibrationWindow
{
public:
  struct Sample
  {
    ImuSample sample;
    double dt;  ///< since the previous sample [s]
  };

  void clear()
  {
    samples_.clear();
    forgetSums();
  }
  bool empty() const
  {
    return samples_.empty();
  }
  const std::vector<Sample>& samples() const
  {
    return samples_;
  }
  /// The samples, handed over; the window is then empty.
  std::vector<Sample> take()
  {
    std::vector<Sample> taken;
    taken.swap(samples_);
    forgetSums();
    return taken;
  }
  /// Room for n samples, so that adding them moves none (a window of seconds at a high rate is
  /// megabytes to copy in one sample's call).
  void reserve(std::size_t n)
  {
    samples_.reserve(n);
    for (auto& axis : level_axes_)
      axis.reserve(n);
  }
  /// Adds a sample; whether the window now spans `duration` [s] from its first sample.
  bool add(const ImuSample& sample, double dt, double duration);

  /// The bias so far, given this sample's level acceleration: the mean of those given since the
  /// window's first sample [m/s^2].
  Vector3 provisionalBias(const Vector3& level_acceleration);

  /// The level acceleration of the newest sample, as the owner found it while the window filled:
  /// kept for levelAxes() where the sample has its own orientation (the level frame then does not
  /// wait for the window's end), so that the window's end does not level every sample again.
  void noteLevel(const Vector3& level_acceleration);

  /// Mean specific force of the window [m/s^2] (summed as the samples came); *any_without_orientation:
  /// some sample had no orientation.
  Vector3 meanSpecificForce(bool* any_without_orientation) const;

  /// Each level axis's samples, by `level` (the sample's level acceleration): those noted, the rest
  /// by `level`; every sample by `level` when one had no orientation. Once per window: the noted
  /// values are handed over.
  std::array<std::vector<double>, 3> levelAxes(const std::function<Vector3(const ImuSample&)>& level);

  /// Paper Table 1: the mean over the window of the velocity integrated from the level
  /// acceleration less `bias` [m/s].
  Vector3 constantPositionDrift(const std::function<Vector3(const ImuSample&)>& level, const Vector3& bias) const;

private:
  void forgetSums()
  {
    force_sum_ = Vector3::Zero();
    any_without_orientation_ = false;
    for (auto& axis : level_axes_)
      axis.clear();
  }

  std::vector<Sample> samples_;
  double start_ = 0.0;  ///< time of the first sample [s]
  Vector3 provisional_sum_ = Vector3::Zero();
  Vector3 force_sum_ = Vector3::Zero();  ///< of the samples' specific force, in order
  bool any_without_orientation_ = false;
  /// The noted level accelerations of the first samples, per axis (none once a sample without
  /// orientation came).
  std::array<std::vector<double>, 3> level_axes_;
};
}  // namespace periodic_bias_compensation
