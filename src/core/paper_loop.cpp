#include "periodic_bias_compensation/core/paper_loop.h"

#include <algorithm>
#include <cmath>

namespace periodic_bias_compensation
{
PaperLoop::PaperLoop(int capacity) : v_table_(capacity), y_table_(capacity)
{
}

void PaperLoop::setCapacity(int capacity)
{
  v_table_ = SignalHistory(capacity);
  y_table_ = SignalHistory(capacity);
  reset();
}

void PaperLoop::reset()
{
  v_table_.clear();
  y_table_.clear();
  v_ = y_ = 0.0;
  y_sum_ = v_sum_ = 0.0;
  sum_window_ = 0;
  residual_variance_ = 0.0;
}

PaperOutput PaperLoop::step(const PaperStep& in, const AxisGains& g)
{
  const int period = in.period;
  const double dt = in.dt;
  PaperOutput out;
  out.periodic = period >= kMinPaperPeriod && v_table_.size() >= period && period <= v_table_.capacity();

  double v = v_ + in.acceleration * dt;  // Eq. 2
  if (out.periodic)
  {
    out.d_v = g.beta_v * v_table_.midRange(period) + g.alpha_v * (v - v_table_.ago(period));  // Eq. 6
    v -= out.d_v / period;                                                                    // Eq. 3
  }
  double y = y_ + (v - in.constant_drift) * dt;  // Eq. 4
  if (out.periodic)
  {
    out.d_p = g.beta_p * y_table_.midRange(period) + g.alpha_p * (y - y_table_.ago(period));  // Eq. 7
    y -= out.d_p / period;                                                                    // Eq. 5
  }
  v_ = v;
  y_ = y;
  double y_slow = 0.0, v_slow = 0.0;
  pushAndAverage(y, v, out.periodic ? period : 1, &y_slow, &v_slow);
  out.position_filtered = y_slow;
  out.velocity_filtered = v_slow;
  out.position_wave = y - y_slow;
  out.velocity_wave = v - v_slow;
  out.periodic_bias = out.periodic ? out.d_v / (period * dt > 0.0 ? period * dt : 1.0) : 0.0;

  // Integrated white noise since the last reset: no bound is claimed for the paper's loop.
  const double beta = dt > 0.0 ? 1.0 - std::exp(-dt / in.memory) : 0.0;
  residual_variance_ = (1.0 - beta) * residual_variance_ + beta * in.acceleration * in.acceleration;
  const double density = 2.0 * residual_variance_ * dt;
  const double t = in.time_since_reset;
  out.position_variance = density * t * t * t / 3.0;
  out.velocity_variance = density * t;
  return out;
}

void PaperLoop::pushAndAverage(double y, double v, int window, double* y_mean, double* v_mean)
{
  y_table_.push(y);
  v_table_.push(v);
  window = std::min(window, y_table_.size());
  if (window != sum_window_)
  {
    sum_window_ = window;
    y_sum_ = v_sum_ = 0.0;
    for (int k = 1; k <= window; ++k)
    {
      y_sum_ += y_table_.ago(k);
      v_sum_ += v_table_.ago(k);
    }
  }
  else
  {
    y_sum_ += y - (y_table_.size() > window ? y_table_.ago(window + 1) : 0.0);
    v_sum_ += v - (v_table_.size() > window ? v_table_.ago(window + 1) : 0.0);
  }
  *y_mean = y_sum_ / std::max(1, window);
  *v_mean = v_sum_ / std::max(1, window);
}

}  // namespace periodic_bias_compensation
