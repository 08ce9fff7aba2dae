#include "periodic_bias_compensation/core/heave_filter.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Core>

namespace periodic_bias_compensation
{
namespace
{
/// x solving a x = b for a symmetric positive definite a (its lower triangle read): Cholesky,
/// written out for the fixed size. Eigen's LLT and LDLT run their general blocked code even on a
/// 4 x 4, measurably slower for a solve made once per sample while the start correction runs.
template <int N>
Eigen::Matrix<double, N, 1> solvePositiveDefinite(const Eigen::Matrix<double, N, N>& a,
                                                  const Eigen::Matrix<double, N, 1>& b)
{
  double l[N][N] = {};
  for (int j = 0; j < N; ++j)
  {
    double diagonal = a(j, j);
    for (int k = 0; k < j; ++k)
      diagonal -= l[j][k] * l[j][k];
    l[j][j] = std::sqrt(diagonal);
    for (int i = j + 1; i < N; ++i)
    {
      double value = a(i, j);
      for (int k = 0; k < j; ++k)
        value -= l[i][k] * l[j][k];
      l[i][j] = value / l[j][j];
    }
  }
  Eigen::Matrix<double, N, 1> x;
  for (int i = 0; i < N; ++i)  // l y = b
  {
    double value = b[i];
    for (int k = 0; k < i; ++k)
      value -= l[i][k] * x[k];
    x[i] = value / l[i][i];
  }
  for (int i = N - 1; i >= 0; --i)  // l^T x = y
  {
    double value = x[i];
    for (int k = i + 1; k < N; ++k)
      value -= l[k][i] * x[k];
    x[i] = value / l[i][i];
  }
  return x;
}
}  // namespace

HeaveFilter::HeaveFilter(double corner_frequency)
{
  setCornerFrequency(corner_frequency);
}

void HeaveFilter::setCornerFrequency(double corner_frequency)
{
  if (!(corner_frequency > 0.0) || !std::isfinite(corner_frequency))
    throw std::invalid_argument("HeaveFilter: the corner frequency must be finite and > 0");
  omega_ = 2.0 * M_PI * corner_frequency;
  const double w = omega_;
  k_ = { 4.0 * w, 6.0 * w * w, 4.0 * w * w * w, w * w * w * w };
  reset();
}

void HeaveFilter::reset()
{
  q_.setZero();
  previous_a_ = 0.0;
  started_ = false;
  elapsed_ = 0.0;
  normal_.setZero();
  moments_.setZero();
  coefficients_.setZero();
}

// Observer canonical form of G = (s^2 + 4 w s) / (s + w)^4: the input enters the second state
// with gain 1 and the third with gain 4 w; q_[0] is the output.
HeaveFilter::State HeaveFilter::derivative(const State& q, double a) const
{
  State d;
  d[0] = -k_[0] * q[0] + q[1];
  d[1] = -k_[1] * q[0] + q[2] + a;
  d[2] = -k_[2] * q[0] + q[3] + 4.0 * omega_ * a;
  d[3] = -k_[3] * q[0];
  return d;
}

HeaveOutput HeaveFilter::update(double a, double dt)
{
  if (!started_)
  {
    started_ = true;
  }
  else if (dt > 0.0)
  {
    // Heun's method with the input linear over the step: second order in omega dt, so at 50 Hz
    // a 0.1 Hz wave is integrated with a relative error of ~1e-5. The poles (w dt ~ 1e-3) are
    // far inside its stability region.
    const State d1 = derivative(q_, previous_a_);
    const State d2 = derivative(q_ + dt * d1, a);
    q_ += 0.5 * dt * (d1 + d2);
    elapsed_ += dt;
  }
  previous_a_ = a;

  HeaveOutput out;
  out.position = q_[0];
  out.velocity = -k_[0] * q_[0] + q_[1];
  out.acceleration = -k_[0] * out.velocity - k_[1] * q_[0] + q_[2] + a;

  const double x = omega_ * elapsed_;
  if (x >= kHeaveStartSpan)
    return out;
  // Free responses (w t)^k exp(-w t) / k!, their first and second time derivatives
  // (d/dt phi_k = w (phi_{k-1} - phi_k)).
  State phi, dphi, ddphi;
  const double decay = std::exp(-x);
  double power = 1.0;
  for (int k = 0; k < kOrder; ++k)
  {
    phi[k] = power * decay;
    power *= x / (k + 1);
  }
  for (int k = 0; k < kOrder; ++k)
    dphi[k] = omega_ * ((k > 0 ? phi[k - 1] : 0.0) - phi[k]);
  for (int k = 0; k < kOrder; ++k)
    ddphi[k] = omega_ * ((k > 0 ? dphi[k - 1] : 0.0) - dphi[k]);
  const Eigen::Matrix<double, kOrder, kOrder> normal = normal_ + phi * phi.transpose();
  const State moments = moments_ + phi * out.position;
  // Late in the span the free responses fall below the sums' precision: once a sample leaves
  // both unchanged, the fit is the last one, not solved again.
  if (normal != normal_ || moments != moments_)
  {
    normal_ = normal;
    moments_ = moments;
    // A small ridge: until a few samples are in, the normal matrix is singular.
    Eigen::Matrix<double, kOrder, kOrder> regularised = normal_;
    regularised.diagonal().array() += 1e-9 * (1.0 + normal_.trace());
    coefficients_ = solvePositiveDefinite(regularised, moments_);
  }
  out.position -= phi.dot(coefficients_);
  out.velocity -= dphi.dot(coefficients_);
  out.acceleration -= ddphi.dot(coefficients_);
  return out;
}

// |G(j omega)|^2 = omega^2 (omega^2 + 16 w^2) / (omega^2 + w^2)^4; with omega = w x and
// int_0^inf x^(2m) / (1 + x^2)^4 dx = pi / 32 (m = 1, 2), 5 pi / 32 (m = 3):
// int_0^inf |G|^2 df = (pi / 32 + 16 pi / 32) / (2 pi w^3) = 17 / (64 w^3),
// int_0^inf omega^2 |G|^2 df = (5 pi / 32 + 16 pi / 32) / (2 pi w) = 21 / (64 w).
double HeaveFilter::positionVariance(double noise_density_squared) const
{
  return noise_density_squared * 17.0 / (64.0 * omega_ * omega_ * omega_);
}

double HeaveFilter::velocityVariance(double noise_density_squared) const
{
  return noise_density_squared * 21.0 / (64.0 * omega_);
}

}  // namespace periodic_bias_compensation
