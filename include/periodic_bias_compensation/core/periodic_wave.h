// The default mode's periodic model of one level axis over the life of its lock (estimation core,
// no ROS).
//
// While locked, a HarmonicEstimator at the lock's frequency (extrapolated to now by the owner)
// follows the acceleration less the calibrated offset; its displacement and velocity come in
// closed form, drift free, once it has seen one period. A new lock (or one that moved) starts the
// model over at the new frequency, fitted at once to the input over the last period (or the
// memory, if longer) kept in a history, so it describes the wave from the next sample on and the
// slow channel never takes a period of wave while the model fills. A lock that changes or is lost
// fades its model out rather than dropping it: the model is kept, extrapolated at its own
// frequency, and its weight decays with kFadeTime (not longer: on a broad sea the extrapolation
// soon loses the wave's phase). The wave output never steps.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <cmath>

#include "periodic_bias_compensation/core/harmonic_model.h"

namespace periodic_bias_compensation
{
/// One locked sample's model output.
struct PeriodicWaveOutput
{
  double residual = 0.0;  ///< the input less the model's fit [m/s^2]
  bool ready = false;     ///< the model has seen a period: the values below describe the wave
  double acceleration = 0.0, position = 0.0, velocity = 0.0;  ///< [m/s^2], [m], [m/s]
  /// Variances of position and velocity per unit residual variance (HarmonicEstimator::evaluate).
  double position_variance_factor = 0.0, velocity_variance_factor = 0.0;
};

class PeriodicWave
{
public:
  /// Time constant with which the model of a changed or lost lock fades out [s], and the weight
  /// below which it is dropped [-].
  static constexpr double kFadeTime = 2.0;
  static constexpr double kFadeEnd = 1e-3;

  /// Samples of input history kept (the longest period searched, or the memory if longer).
  void setCapacity(int samples)
  {
    history_ = SignalHistory(samples);
  }
  /// Forgets model, fading model and history.
  void reset(int harmonics);

  /// A new lock at `frequency` [Hz]: the current model (if it has seen a period) fades out at its
  /// own frequency, a new one starts, fitted to the history when fit_history (sample rate `rate`
  /// [Hz], memory [s]).
  void start(double frequency, double rate, double memory, int harmonics, bool fit_history,
             double slow_span = INFINITY);
  /// The wave velocity [m/s] that the slow channel integrated while nothing modelled the wave, as
  /// the model fitted at the last start() describes it: its velocity at the previous sample, less
  /// its velocity `slow_span` [s] before when the slow channel started at zero less than a period
  /// ago (an older start the model, fitted to the recent past, does not describe). Zero when the
  /// model needs a period to describe the wave or an older model fades into it (the blend hands
  /// over then). The slow channel gives it up (DriftObserver::shiftVelocity), so that slow plus
  /// wave stays the integral of the measurement: a model fitted to motion that has just stopped
  /// leaves no ramp in it.
  double startVelocity() const
  {
    return start_velocity_;
  }
  /// The lock was lost: its model fades out, extrapolated at the frequency it last followed.
  void retire();

  /// A locked sample: `value` [m/s^2] at `frequency` [Hz] (the lock's, extrapolated to now), dt
  /// [s] after the previous one, at sample rate `rate` [Hz], with the fit's forgetting factor
  /// `lambda` = exp(-dt / memory) (the owner weighs its residual variance with it too).
  PeriodicWaveOutput update(double value, double frequency, double dt, double rate, double lambda);
  /// An unlocked sample: only kept in the history.
  void push(double value)
  {
    history_.push(value);
  }
  /// Blends the fading model into a wave estimate (acceleration, position, velocity) by its
  /// weight, which then decays over dt [s].
  void fade(double dt, double* acceleration, double* position, double* velocity);

private:
  HarmonicEstimator model_;
  bool ready_ = false;  ///< model_ has described a period: its output is used
  double phase_ = 0.0;
  double frequency_ = 0.0;       ///< the frequency model_ last followed [Hz]
  double start_velocity_ = 0.0;  ///< startVelocity()
  HarmonicEstimator previous_;   ///< the model of a lock that changed or was lost
  double previous_frequency_ = 0.0, previous_phase_ = 0.0, previous_weight_ = 0.0;
  SignalHistory history_;  ///< the model's input
};
}  // namespace periodic_bias_compensation
