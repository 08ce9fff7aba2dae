// The default mode's harmonic model and the histories it runs on (estimation core, no ROS).
//
// HarmonicEstimator fits [1, cos k phi, sin k phi], k = 1..H, to a signal by recursive least
// squares with exponential forgetting, phi the phase of the tracked frequency, and gives the
// periodic part's displacement and velocity in closed form. SignalHistory keeps the last values
// of a signal with the value L samples ago and a sliding mid-range.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "periodic_bias_compensation/core/zeroed_buffer.h"

namespace periodic_bias_compensation
{
/// Most harmonics of the dominant frequency the model takes.
constexpr int kMaxHarmonics = 4;

/// Last values of a signal with O(1) access to the value L samples ago and an amortised O(1)
/// sliding mid-range (max + min) / 2 over the last L samples (monotonic deques).
class SignalHistory
{
public:
  explicit SignalHistory(int capacity = 1) : values_(static_cast<std::size_t>(std::max(capacity, 1)))
  {
  }

  void push(double value)
  {
    values_[index_ % values_.size()] = value;
    pushExtremes(index_, value);
    ++index_;
  }
  int size() const
  {
    return static_cast<int>(std::min<long>(index_, static_cast<long>(values_.size())));
  }
  int capacity() const
  {
    return static_cast<int>(values_.size());
  }
  /// Value pushed `lag` pushes ago (lag 1 = newest).
  double ago(int lag) const
  {
    return values_[(index_ - lag) % static_cast<long>(values_.size())];
  }
  /// (max + min) / 2 over the last `window` values (window <= size()).
  double midRange(int window)
  {
    if (window != window_)
    {
      window_ = window;
      rebuildExtremes();
    }
    return 0.5 * (values_[max_.front() % values_.size()] + values_[min_.front() % values_.size()]);
  }
  void clear()
  {
    index_ = 0;
    max_.clear();
    min_.clear();
  }

private:
  void pushExtremes(long index, double value)
  {
    if (window_ <= 0)
      return;
    while (!max_.empty() && values_[max_.back() % values_.size()] <= value)
      max_.pop_back();
    max_.push_back(index);
    while (!min_.empty() && values_[min_.back() % values_.size()] >= value)
      min_.pop_back();
    min_.push_back(index);
    while (max_.front() <= index - window_)
      max_.pop_front();
    while (min_.front() <= index - window_)
      min_.pop_front();
  }
  void rebuildExtremes()
  {
    max_.clear();
    min_.clear();
    const long first = std::max(0L, index_ - window_);
    for (long i = first; i < index_; ++i)
      pushExtremes(i, values_[i % values_.size()]);
  }

  ZeroedBuffer values_;  ///< sized for the rate: its pages are faulted in as it fills
  long index_ = 0;
  int window_ = 0;
  std::deque<long> max_, min_;
};

/// Recursive least squares with exponential forgetting on [1, cos(k phi), sin(k phi)], k=1..H.
/// Plain fixed-size arrays and loops over the H used (at most 9 parameters): Eigen's dynamic-size
/// products cost several times more at this size. No heap allocation.
class HarmonicEstimator
{
  static constexpr int kMaxParameters = 1 + 2 * kMaxHarmonics;
  using Vector = std::array<double, kMaxParameters>;

public:
  void reset(int harmonics)
  {
    harmonics_ = harmonics;
    n_ = 1 + 2 * harmonics;
    theta_.fill(0.0);
    for (auto& row : covariance_)
      row.fill(0.0);
    for (int i = 0; i < n_; ++i)
      covariance_[i][i] = 1e4;
    regressor_phase_ = NAN;
    updates_ = 0;
  }
  /// One update with forgetting factor lambda; returns the a-priori residual.
  double update(double phase, double value, double lambda)
  {
    fillRegressor(phase);
    const Vector& h = regressor_;
    double prediction = 0.0;
    for (int i = 0; i < n_; ++i)
      prediction += theta_[i] * h[i];
    const double residual = value - prediction;
    Vector g;  // P h
    double denominator = lambda;
    for (int i = 0; i < n_; ++i)
    {
      g[i] = 0.0;
      for (int j = 0; j < n_; ++j)
        g[i] += covariance_[i][j] * h[j];
      denominator += h[i] * g[i];
    }
    const double inverse = 1.0 / denominator;
    for (int i = 0; i < n_; ++i)
      theta_[i] += g[i] * inverse * residual;
    // P = (P - P h h' P / denominator) / lambda, computed on one triangle and mirrored so that
    // rounding cannot make it asymmetric (or indefinite).
    const double inverse_lambda = 1.0 / lambda;
    for (int i = 0; i < n_; ++i)
      for (int j = i; j < n_; ++j)
        covariance_[i][j] = covariance_[j][i] = (covariance_[i][j] - g[i] * g[j] * inverse) * inverse_lambda;
    ++updates_;
    return residual;
  }
  /// Right after reset(): the state that `count` update()s would leave (the k-th, k = 0 ..
  /// count - 1, at phase first_phase + k step with value(k), all with forgetting factor lambda),
  /// equal to it up to rounding and a few times cheaper: the exponentially weighted normal
  /// equations are summed in one pass and solved once. Fits a new model to a stretch of history.
  template <class Value>
  void fit(int count, double first_phase, double step, double lambda, const Value& value)
  {
    // RLS from P0 = 1e4 I and theta = 0 minimises sum lambda^(count-1-k) e_k^2 + lambda^count
    // theta' P0^-1 theta: information A = lambda A + h h', A_0 = P0^-1; b = lambda b + h y.
    using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxParameters, kMaxParameters>;
    using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxParameters, 1>;
    Matrix information = Matrix::Zero(n_, n_);  // its upper triangle
    Column weighted = Column::Zero(n_);
    for (int i = 0; i < n_; ++i)
      information(i, i) = 1.0 / covariance_[i][i];
    Vector h{};
    h[0] = 1.0;
    double c1 = 0.0, s1 = 0.0;
    const double step_c = std::cos(step), step_s = std::sin(step);
    for (int k = 0; k < count; ++k)
    {
      // The fundamental by rotation, from sin/cos again every kReanchor samples.
      if (k % kReanchor == 0)
      {
        c1 = std::cos(first_phase + k * step);
        s1 = std::sin(first_phase + k * step);
      }
      else
      {
        const double next_c = c1 * step_c - s1 * step_s;
        s1 = s1 * step_c + c1 * step_s;
        c1 = next_c;
      }
      fillHarmonics(c1, s1, &h);
      const double y = value(k);
      for (int i = 0; i < n_; ++i)
      {
        weighted[i] = lambda * weighted[i] + h[i] * y;
        for (int j = i; j < n_; ++j)
          information(i, j) = lambda * information(i, j) + h[i] * h[j];
      }
    }
    // P = A^-1 by Cholesky, theta = P b.
    const Matrix p = information.selfadjointView<Eigen::Upper>().llt().solve(Matrix::Identity(n_, n_));
    const Column theta = p * weighted;
    for (int i = 0; i < n_; ++i)
    {
      theta_[i] = theta[i];
      for (int j = i; j < n_; ++j)
        covariance_[i][j] = covariance_[j][i] = p(i, j);
    }
    regressor_phase_ = NAN;
    updates_ += count;
  }
  /// Periodic part (without the constant) of the acceleration, its displacement and velocity
  /// for the current phase; omega [rad/s] is the fundamental. variance_factor: h' P h of the
  /// displacement (multiply by the residual variance).
  void evaluate(double phase, double omega, double* acceleration, double* position, double* velocity,
                double* variance_factor, double* velocity_variance_factor)
  {
    fillRegressor(phase);
    double a = 0.0, x = 0.0, v = 0.0;
    Vector dx, dv;
    dx[0] = dv[0] = 0.0;
    for (int k = 1; k <= harmonics_; ++k)
    {
      const double c = regressor_[2 * k - 1], s = regressor_[2 * k];
      const double ck = theta_[2 * k - 1], sk = theta_[2 * k];
      const double w = k * omega;
      a += ck * c + sk * s;
      x += -(ck * c + sk * s) / (w * w);
      v += (ck * s - sk * c) / w;
      dx[2 * k - 1] = -c / (w * w);
      dx[2 * k] = -s / (w * w);
      dv[2 * k - 1] = s / w;
      dv[2 * k] = -c / w;
    }
    *acceleration = a;
    *position = x;
    *velocity = v;
    *variance_factor = quadraticForm(dx);
    *velocity_variance_factor = quadraticForm(dv);
  }
  double constant() const
  {
    return theta_[0];
  }

  long updates() const
  {
    return updates_;
  }

private:
  /// [1, cos(k phi), sin(k phi)] with one sin/cos call (angle-sum recurrence), kept for a
  /// second call at the same phase.
  void fillRegressor(double phase)
  {
    if (phase == regressor_phase_)
      return;
    regressor_phase_ = phase;
    regressor_[0] = 1.0;
    fillHarmonics(std::cos(phase), std::sin(phase), &regressor_);
  }
  /// cos(k phi), sin(k phi), k = 1..harmonics_, into h[1..] from those of the fundamental.
  void fillHarmonics(double c1, double s1, Vector* h) const
  {
    double c = c1, s = s1;
    for (int k = 1; k <= harmonics_; ++k)
    {
      (*h)[2 * k - 1] = c;
      (*h)[2 * k] = s;
      const double next_c = c * c1 - s * s1;
      s = s * c1 + c * s1;
      c = next_c;
    }
  }
  double quadraticForm(const Vector& d) const
  {
    double sum = 0.0;
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j)
        sum += d[i] * covariance_[i][j] * d[j];
    return sum;
  }

  /// fit(): samples between two sin/cos calls of the fundamental (the rotation in between drifts
  /// by rounding about a 1e-16 per step).
  static constexpr int kReanchor = 256;

  int harmonics_ = 1;
  int n_ = 3;
  Vector theta_{}, regressor_{};
  std::array<Vector, kMaxParameters> covariance_{};
  double regressor_phase_ = NAN;
  long updates_ = 0;
};

/// Least-squares constant of [1, cos k phi, sin k phi], k = 1..harmonics, phi = 2 pi frequency
/// t, fitted over a record sampled at rate [Hz]: the offset of a periodic signal over a window
/// that is not a whole number of periods.
double harmonicConstant(const std::vector<double>& values, double rate, double frequency, int harmonics);

}  // namespace periodic_bias_compensation
