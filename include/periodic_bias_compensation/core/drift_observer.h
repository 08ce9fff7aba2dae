// The default mode's slow-motion channel of one level axis: a fourth-order drift observer
// (estimation core, no ROS).
//
// Its input is the level acceleration less the wave model's. With poles at -w (characteristic
// (s + w)^4, w = 1 / drift_time_constant) its states are position, velocity, the bias and the
// bias's rate: p / a = s^2 / (s + w)^4, so a constant bias and one that changes at a steady rate
// (a slow drift, a long-period wander between its turns) leave no position error, and the
// position is pulled to zero mean with the time constant.
//
// The Euler step is stable only while dt < 0.55 drift_time_constant: a longer step (a slow IMU,
// a short gap) is split into steps of at most a tenth of 1 / w; past kMaxSteps the motion starts
// again at zero, as after a gap.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

namespace periodic_bias_compensation
{
class DriftObserver
{
public:
  /// Most Euler steps per update.
  static constexpr int kMaxSteps = 10000;

  /// One sample. acceleration: the level acceleration less the wave model's [m/s^2]; dt: since
  /// the previous sample [s]; time_constant: drift_time_constant [s]; use_bias: the bias is
  /// taken off (enable_constant); learn_bias: the bias and its rate follow (once calibrated).
  void update(double acceleration, double dt, double time_constant, bool use_bias, bool learn_bias);

  /// Position and velocity of the slow motion [m], [m/s].
  double position() const
  {
    return p_;
  }
  double velocity() const
  {
    return v_ - k1_ * p_;
  }
  /// The bias estimate [m/s^2] (the constant bias until it learns), and its rate [m/s^3].
  double bias() const
  {
    return bias_;
  }
  void setBias(double bias)
  {
    bias_ = bias;
  }
  double biasRate() const
  {
    return bias_rate_;
  }
  /// The last update's corrections: velocity [m/s] and position [m] over its dt (d_v, d_p as the
  /// paper names them).
  double velocityCorrection() const
  {
    return d_v_;
  }
  double positionCorrection() const
  {
    return d_p_;
  }
  /// The motion starts again at zero (position, velocity and the bias's rate); the bias is kept.
  void restartMotion()
  {
    p_ = v_ = bias_rate_ = 0.0;
  }
  /// The velocity changes by dv [m/s] (motion handed to or taken from the wave channel).
  void shiftVelocity(double dv)
  {
    v_ += dv;
  }
  /// Position and velocity restart at zero; the bias and its rate are kept.
  void restartPosition()
  {
    p_ = v_ = 0.0;
  }

  /// Variances of position [m^2] and velocity [m^2/s^2] for white acceleration noise of
  /// variance `acceleration_variance` [m^2/s^4] per sample at `rate` [Hz] (one-sided density
  /// 2 sigma^2 / rate) through the observer: n^2 / (64 w^3) and 5 n^2 / (64 w), the closed forms
  /// of a quadruple pole at -w.
  static void noiseVariances(double acceleration_variance, double rate, double time_constant, double* position,
                             double* velocity);

private:
  double p_ = 0.0, v_ = 0.0, bias_ = 0.0, bias_rate_ = 0.0;
  double k1_ = 0.0;  ///< the last update's position gain 4 w [1/s]
  double d_v_ = 0.0, d_p_ = 0.0;
};
}  // namespace periodic_bias_compensation
