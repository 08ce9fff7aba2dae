// The paper's repetitive compensator for one level axis, Eq. 2-7 as written (estimation core,
// no ROS; docs/algorithm.md, "Paper mode").
//
//   v_k = v_{k-1} + a_k dt - d_v / L,   d_v = beta_v mid(v over L) + alpha_v (v_k - v_{k-L})
//   y_k = y_{k-1} + (v_k - c) dt - d_p / L,   d_p = beta_p mid(y over L) + alpha_p (y_k - y_{k-L})
//
// with L the period in samples, mid the mid-range (max + min) / 2 over the last L values and c
// the calibration window's mean velocity (Table 1's constant position drift). The slow motion is
// the mean of y and v over the last L samples, the wave motion what is left.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/harmonic_model.h"

namespace periodic_bias_compensation
{
/// One sample of one axis.
struct PaperStep
{
  double acceleration = 0.0;      ///< level acceleration less the constant bias [m/s^2]
  double dt = 0.0;                ///< [s]
  int period = 0;                 ///< L [samples]; below kMinPaperPeriod: no periodic compensation
  double constant_drift = 0.0;    ///< c [m/s]
  double memory = 3.0;            ///< time constant of the residual variance [s]
  double time_since_reset = 0.0;  ///< [s], for the variance of the integrated noise
};

struct PaperOutput
{
  bool periodic = false;  ///< the periodic compensation ran (a period, and L values recorded)
  double position_filtered = 0.0, velocity_filtered = 0.0;  ///< [m], [m/s]
  double position_wave = 0.0, velocity_wave = 0.0;
  double d_v = 0.0, d_p = 0.0;                              ///< this step's drift terms (Eq. 6, 7)
  double periodic_bias = 0.0;                               ///< d_v / (L dt) [m/s^2]
  double position_variance = 0.0, velocity_variance = 0.0;  ///< integrated white noise
};

class PaperLoop
{
public:
  /// capacity: the longest period planned [samples].
  explicit PaperLoop(int capacity = 1);

  /// Forgets the integrals and tables (capacity kept).
  void reset();
  /// The longest period planned [samples]; forgets everything.
  void setCapacity(int capacity);

  PaperOutput step(const PaperStep& in, const AxisGains& gains);

private:
  /// Appends (y, v) to the tables; their means over the last `window` samples (running sums,
  /// O(1) per sample while the window stays the same).
  void pushAndAverage(double y, double v, int window, double* y_mean, double* v_mean);

  SignalHistory v_table_, y_table_;
  double v_ = 0.0, y_ = 0.0;
  double y_sum_ = 0.0, v_sum_ = 0.0;
  int sum_window_ = 0;
  double residual_variance_ = 0.0;
};

}  // namespace periodic_bias_compensation
