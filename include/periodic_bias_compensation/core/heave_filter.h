// Broadband heave: the vertical wave motion from the level vertical acceleration (estimation
// core, no ROS).
//
// A harmonic model of one dominant period describes a narrow sea; a JONSWAP sea spreads its heave
// over a band, and most of it then falls outside the model. HeaveFilter integrates the whole
// band instead: position = G(s) a with G = H(s) / s^2, H the binomial drift removal of order 4,
//
//   H = (1 - L)^4 + 4 L (1 - L)^3 = s^3 (s + 4 w) / (s + w)^4,   L = w / (s + w),
//
// so G = s (s + 4 w) / (s + w)^4. H has a triple zero at DC: a constant acceleration bias, an
// unknown initial velocity or position leave no position error in steady state. In the wave band
// its error is 1 - H = 6 L^2 (1 - L)^2 + 4 L^3 (1 - L) + L^4, about 6 (w / omega)^2: 1 % of the
// wave amplitude at 20 x the corner frequency.
//
// Start: a filter started from rest reads the ship's heave velocity at the first sample (tens of
// cm/s) and the calibration error of the bias as a step, and rings for minutes (measured in
// docs/benchmarks.md, "Heave filter start"). Every such start is a sum of the
// filter's free responses, which span (w t)^k exp(-w t), k = 0..3. The filter therefore runs from
// rest, and the combination of free responses that best explains its output so far (least
// squares over every sample since the start) is taken off: a wave has no such slowly decaying
// component. Causal (the output at t uses samples up to t only); once w t exceeds
// kHeaveStartSpan the free responses are below 1e-20 and the correction stops.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <array>

#include <Eigen/Core>

namespace periodic_bias_compensation
{
/// w t beyond which the start correction is no longer computed (its basis is below 1e-20).
constexpr double kHeaveStartSpan = 60.0;

/// One step's output of HeaveFilter.
struct HeaveOutput
{
  double position = 0.0;      ///< wave displacement [m]
  double velocity = 0.0;      ///< [m/s]
  double acceleration = 0.0;  ///< the part of the input taken as wave acceleration [m/s^2]
};

class HeaveFilter
{
public:
  static constexpr int kOrder = 4;

  /// corner_frequency [Hz] > 0: the wave band should start at 5-10 times it.
  explicit HeaveFilter(double corner_frequency = 0.015);

  /// Starts from rest; the next sample is the first of a new record.
  void reset();
  void setCornerFrequency(double corner_frequency);
  double cornerFrequency() const
  {
    return omega_ / (2.0 * M_PI);
  }

  /// Takes the vertical acceleration a [m/s^2] (gravity removed; any constant bias left is
  /// harmless) dt [s] after the previous sample (ignored for the first one).
  HeaveOutput update(double a, double dt);

  /// Steady-state variance of the position [m^2] for white acceleration noise of one-sided
  /// density noise_density^2 [(m/s^2)^2/Hz]: noise_density^2 x integral of |G(j 2 pi f)|^2 df.
  double positionVariance(double noise_density_squared) const;
  /// The same for the velocity [m^2/s^2].
  double velocityVariance(double noise_density_squared) const;

private:
  using State = Eigen::Matrix<double, kOrder, 1>;
  State derivative(const State& q, double a) const;

  double omega_ = 0.0;              ///< corner [rad/s]
  std::array<double, kOrder> k_{};  ///< (s + w)^4 = s^4 + k0 s^3 + k1 s^2 + k2 s + k3
  State q_ = State::Zero();         ///< observer canonical form, q_[0] the position from rest
  double previous_a_ = 0.0;
  bool started_ = false;
  double elapsed_ = 0.0;  ///< time since the first sample [s]
  // Least-squares start correction: normal equations of the free responses against the output.
  Eigen::Matrix<double, kOrder, kOrder> normal_ = Eigen::Matrix<double, kOrder, kOrder>::Zero();
  State moments_ = State::Zero();
  State coefficients_ = State::Zero();
};

}  // namespace periodic_bias_compensation
