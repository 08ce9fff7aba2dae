#include "periodic_bias_compensation/core/toeplitz.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace periodic_bias_compensation
{
bool solveToeplitz(const std::vector<double>& t, const std::vector<std::vector<double>>& b,
                   std::vector<std::vector<double>>* x)
{
  const int n = static_cast<int>(t.size());
  if (n == 0 || !(t[0] > 0.0))
    return false;
  for (const std::vector<double>& column : b)
    if (static_cast<int>(column.size()) < n)
      return false;
  std::vector<double> forward(n, 0.0), next(n, 0.0);
  x->assign(b.size(), std::vector<double>(n, 0.0));
  forward[0] = 1.0 / t[0];
  for (std::size_t c = 0; c < b.size(); ++c)
    (*x)[c][0] = b[c][0] / t[0];
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
    forward.swap(next);
    // Each right-hand side takes the same forward vector.
    for (std::size_t c = 0; c < b.size(); ++c)
    {
      std::vector<double>& solution = (*x)[c];
      double ex = 0.0;
      for (int i = 0; i < m; ++i)
        ex += t[m - i] * solution[i];
      const double correction = b[c][m] - ex;
      // Backward vector: forward reversed.
      for (int i = 0; i <= m; ++i)
        solution[i] += correction * forward[m - i];
    }
  }
  return true;
}

bool solveToeplitz(const std::vector<double>& t, const std::vector<double>& b, std::vector<double>* x)
{
  std::vector<std::vector<double>> solutions;
  if (!solveToeplitz(t, { b }, &solutions))
    return false;
  *x = std::move(solutions[0]);
  return true;
}

namespace
{
/// solveBlockToeplitz() with the solution kept as n blocks of 3 x Columns (fixed-size products
/// where the number of right-hand sides is known at compile time).
template <int Columns>
bool solveBlocks(const std::vector<Eigen::Matrix3d>& r, const Eigen::MatrixXd& b, Eigen::MatrixXd* x)
{
  using Eigen::Matrix3d;
  using Block = Eigen::Matrix<double, 3, Columns>;
  const int n = static_cast<int>(r.size());
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
  std::vector<Block> solution(n, Block::Zero(3, columns));
  solution[0] = q_llt.solve(b.topRows<3>());
  Block eta(3, columns);
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
    next_forward[0] = forward[0];
    next_backward[0] = -forward[0] * backward_step;
    for (int i = 1; i <= m; ++i)
    {
      next_forward[i].noalias() = forward[i] - backward[i - 1] * forward_step;
      next_backward[i].noalias() = backward[i - 1] - forward[i] * backward_step;
    }
    next_forward[m + 1].noalias() = -backward[m] * forward_step;
    next_backward[m + 1] = backward[m];
    forward.swap(next_forward);
    backward.swap(next_backward);
    p -= delta.transpose() * forward_step;
    q -= delta * backward_step;
    if (!factor(q, &q_llt))
      return false;
    // T_(m+1) [x; 0] = [b_0..b_m; eta]: the new backward vector makes up the last block.
    eta.setZero();
    for (int i = 0; i <= m; ++i)
      eta.noalias() += r[m + 1 - i] * solution[i];
    const Block correction = q_llt.solve(b.middleRows<3>(3 * (m + 1)) - eta);
    for (int i = 0; i <= m + 1; ++i)
      solution[i].noalias() += backward[i] * correction;
  }
  x->resize(3 * n, columns);
  for (int i = 0; i < n; ++i)
    x->middleRows<3>(3 * i) = solution[i];
  return true;
}
}  // namespace

bool solveBlockToeplitz(const std::vector<Eigen::Matrix3d>& r, const Eigen::MatrixXd& b, Eigen::MatrixXd* x)
{
  const int n = static_cast<int>(r.size());
  if (n == 0 || b.rows() != 3 * n)
    return false;
  // The Wiener designs solve for displacement and velocity: two right-hand sides.
  return b.cols() == 2 ? solveBlocks<2>(r, b, x) : solveBlocks<Eigen::Dynamic>(r, b, x);
}

}  // namespace periodic_bias_compensation
