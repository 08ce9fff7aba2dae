// Keeps the wave output to what the measured acceleration shows (estimation core, no ROS).
//
// The wave models extrapolate: the harmonic model follows its lock with a memory of several
// periods, and the spectral heave filter is a FIR over several peak periods, which for a narrow
// spectrum behaves like an oscillator. When the motion stops (a hand-held lift put down, a sensor
// laid on a table after a swing), both go on describing a wave that is gone, for as long as their
// memory or span, and a sensor at rest shows centimetres to metres of wave motion. At sea the wave
// the models describe is the one being measured; the check acts there only where the output's
// acceleration is rougher than the measured one (the first designs of a spectral record).
//
// WaveConsistency compares the acceleration of the wave output (the difference of its velocity
// over a step) with the measured acceleration, both in the same band (less their mean over
// 1 / (2 pi min_frequency), which takes off bias and gravity mismatch, then two first-order
// low-passes at kBandTop, which take off most of the white noise and of the output's
// sample-to-sample roughness) and both as mean squares over kAveraging. An output whose
// acceleration holds more than kExcess times the measured power, the white noise's in the band
// added (over so short a mean the noise can cancel part of a weak wave), describes motion that is
// not there: the weight it returns scales the output down to that power,
// sqrt(kExcess (P_measured + P_noise) / P_output); otherwise it is 1. The weight follows the mean
// squares, so a wave that has stopped fades out over a few kAveraging and never steps; an
// estimate in phase with the wave is never scaled, one that lags it by a few tens of degrees at
// most by a little near its zero crossings. The first kSettle of data are not judged.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <array>
#include <cmath>

namespace periodic_bias_compensation
{
class WaveConsistency
{
public:
  static constexpr double kExcess = 4.0;     ///< output / measured acceleration power allowed [-]
  static constexpr double kBandTop = 2.0;    ///< corner of the low-passes [Hz]
  static constexpr double kAveraging = 0.5;  ///< time constant of the mean squares [s]
  static constexpr double kSettle = 2.0;     ///< data before the first judgement [s]

  /// min_frequency [Hz]: the lowest wave frequency (the slow means' corner).
  explicit WaveConsistency(double min_frequency = 0.04) : min_frequency_(min_frequency)
  {
  }
  void setMinFrequency(double min_frequency)
  {
    min_frequency_ = min_frequency;
    reset();
  }
  /// Forgets everything; the next sample starts again.
  void reset();

  /// Takes the measured acceleration [m/s^2] (level, its calibrated offset taken off), the wave
  /// velocity about to be published [m/s], the white-noise variance of the measured acceleration
  /// per sample [m^2/s^4] (0 if unknown) and the step dt [s] since the previous sample; returns
  /// the weight (0, 1] to scale the wave output by.
  double update(double measured, double velocity, double noise_variance, double dt);

  /// The last weight returned (1 before any sample).
  double weight() const
  {
    return weight_;
  }

private:
  /// One step's coefficients, shared by both bands.
  struct Coefficients
  {
    double slow = 0.0, low_pass = 0.0, averaging = 0.0;
  };
  /// One signal in the band and its mean square.
  struct Band
  {
    double mean = 0.0;
    std::array<double, 2> low{};
    double power = 0.0;
    /// Returns the mean square.
    double step(double value, const Coefficients& c);
  };

  double min_frequency_;
  Band measured_, output_;
  double previous_velocity_ = 0.0;
  double samples_ = 0.0;
  double elapsed_ = 0.0;          ///< data judged so far [s]
  double coefficients_dt_ = 0.0;  ///< the step the coefficients below are for [s]
  double slow_ = 0.0, low_pass_ = 0.0, averaging_ = 0.0, noise_gain_ = 0.0;
  double weight_ = 1.0;
};

}  // namespace periodic_bias_compensation
