#include "periodic_bias_compensation/core/toeplitz.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace periodic_bias_compensation
{
bool solveToeplitz(const std::vector<double>& t, const std::vector<double>& b, std::vector<double>* x)
{
  const int n = static_cast<int>(t.size());
  if (n == 0 || !(t[0] > 0.0))
    return false;
  std::vector<double> forward(n, 0.0), next(n, 0.0);
  x->assign(n, 0.0);
  forward[0] = 1.0 / t[0];
  (*x)[0] = b[0] / t[0];
  for (int m = 1; m < n; ++m)
  {
    // Error of the forward vector extended by a zero; the backward vector is its reverse.
    double e = 0.0;
    for (int i = 0; i < m; ++i)
      e += t[m - i] * forward[i];
    const double denominator = 1.0 - e * e;
    if (!(denominator > 1e-12))
      return false;
    for (int i = 0; i <= m; ++i)
    {
      const double f = i < m ? forward[i] : 0.0;
      const double g = i > 0 ? forward[m - i] : 0.0;
      next[i] = (f - e * g) / denominator;
    }
    std::copy(next.begin(), next.begin() + m + 1, forward.begin());
    double ex = 0.0;
    for (int i = 0; i < m; ++i)
      ex += t[m - i] * (*x)[i];
    const double correction = b[m] - ex;
    // Backward vector: forward reversed.
    for (int i = 0; i <= m; ++i)
      (*x)[i] += correction * forward[m - i];
  }
  return true;
}

bool solveBlockToeplitz(const std::vector<Eigen::Matrix3d>& r, const Eigen::MatrixXd& b, Eigen::MatrixXd* x)
{
  using Eigen::Matrix3d;
  const int n = static_cast<int>(r.size());
  if (n == 0 || b.rows() != 3 * n)
    return false;
  const double scale = r[0].trace() / 3.0;
  if (!(scale > 0.0))
    return false;
  // A prediction error's covariance is positive definite while the matrix is: Cholesky's factor,
  // its smallest pivot relative to R(0)'s scale bounded away from zero.
  const auto factor = [scale](const Matrix3d& m, Eigen::LLT<Matrix3d>* llt) {
    llt->compute(m);
    return llt->info() == Eigen::Success && llt->matrixLLT().diagonal().minCoeff() > 1e-6 * std::sqrt(scale);
  };
  // T_m forward = [P; 0 ...], forward[0] = I; T_m backward = [... 0; Q], backward[m] = I.
  std::vector<Matrix3d> forward(n), backward(n), next_forward(n), next_backward(n);
  forward[0] = backward[0] = Matrix3d::Identity();
  Matrix3d p = r[0], q = r[0];
  Eigen::LLT<Matrix3d> p_llt, q_llt;
  if (!factor(q, &q_llt))
    return false;
  const int columns = static_cast<int>(b.cols());
  x->setZero(3 * n, columns);
  x->topRows<3>() = q_llt.solve(b.topRows<3>());
  for (int m = 0; m + 1 < n; ++m)
  {
    // T_(m+1) [forward; 0] = [P; 0; delta], T_(m+1) [0; backward] = [delta^T; 0; Q].
    Matrix3d delta = Matrix3d::Zero();
    for (int i = 0; i <= m; ++i)
      delta.noalias() += r[m + 1 - i] * forward[i];
    if (!factor(p, &p_llt))
      return false;
    const Matrix3d forward_step = q_llt.solve(delta);               // Q^-1 delta
    const Matrix3d backward_step = p_llt.solve(delta.transpose());  // P^-1 delta^T
    for (int i = 0; i <= m + 1; ++i)
    {
      const Matrix3d f = i <= m ? forward[i] : Matrix3d::Zero();
      const Matrix3d g = i >= 1 ? backward[i - 1] : Matrix3d::Zero();
      next_forward[i] = f - g * forward_step;
      next_backward[i] = g - f * backward_step;
    }
    std::copy(next_forward.begin(), next_forward.begin() + m + 2, forward.begin());
    std::copy(next_backward.begin(), next_backward.begin() + m + 2, backward.begin());
    p -= delta.transpose() * forward_step;
    q -= delta * backward_step;
    if (!factor(q, &q_llt))
      return false;
    // T_(m+1) [x; 0] = [b_0..b_m; eta]: the new backward vector makes up the last block.
    Eigen::MatrixXd eta = Eigen::MatrixXd::Zero(3, columns);
    for (int i = 0; i <= m; ++i)
      eta.noalias() += r[m + 1 - i] * x->middleRows<3>(3 * i);
    const Eigen::MatrixXd correction = q_llt.solve(b.middleRows<3>(3 * (m + 1)) - eta);
    for (int i = 0; i <= m + 1; ++i)
      x->middleRows<3>(3 * i).noalias() += backward[i] * correction;
  }
  return true;
}

}  // namespace periodic_bias_compensation
