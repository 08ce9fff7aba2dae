#include "periodic_bias_compensation/core/toeplitz.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace periodic_bias_compensation
{
bool solveToeplitz(const std::vector<double>& t, const std::vector<std::vector<double>>& b,
                   std::vector<std::vector<double>>* x)
{
  using Eigen::VectorXd;
  const int n = static_cast<int>(t.size());
  if (n == 0 || !(t[0] > 0.0))
    return false;
  for (const std::vector<double>& column : b)
    if (static_cast<int>(column.size()) < n)
      return false;
  // t reversed: t[m - i], i = 0..m-1, are its entries n-1-m .. n-2, in a row.
  const VectorXd lags = Eigen::Map<const VectorXd>(t.data(), n).reverse();
  // The forward vector and, beside it, the backward one (its reverse), so that every step is a
  // few contiguous, vectorised passes.
  VectorXd forward = VectorXd::Zero(n), backward = VectorXd::Zero(n);
  VectorXd next_forward = VectorXd::Zero(n), next_backward = VectorXd::Zero(n);
  forward[0] = backward[0] = 1.0 / t[0];
  std::vector<VectorXd> solutions(b.size(), VectorXd::Zero(n));
  for (std::size_t c = 0; c < b.size(); ++c)
    solutions[c][0] = b[c][0] / t[0];
  for (int m = 1; m < n; ++m)
  {
    const auto lag = lags.segment(n - 1 - m, m);
    // Error of the forward vector extended by a zero; the backward vector's is the same.
    const double e = lag.dot(forward.head(m));
    const double denominator = 1.0 - e * e;
    if (!(denominator > 1e-12))
      return false;
    // forward' = ([forward; 0] - e [0; backward]) / d, backward' = ([0; backward] - e [forward; 0]) / d.
    const double scale = 1.0 / denominator;
    next_forward.head(m) = scale * forward.head(m);
    next_forward[m] = 0.0;
    next_forward.segment(1, m) -= (e * scale) * backward.head(m);
    next_backward[0] = 0.0;
    next_backward.segment(1, m) = scale * backward.head(m);
    next_backward.head(m) -= (e * scale) * forward.head(m);
    forward.swap(next_forward);
    backward.swap(next_backward);
    // Each right-hand side takes the same backward vector.
    for (std::size_t c = 0; c < b.size(); ++c)
    {
      VectorXd& solution = solutions[c];
      const double correction = b[c][m] - lag.dot(solution.head(m));
      solution.head(m + 1) += correction * backward.head(m + 1);
    }
  }
  x->resize(b.size());
  for (std::size_t c = 0; c < b.size(); ++c)
    (*x)[c].assign(solutions[c].data(), solutions[c].data() + n);
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
/// out = a + b c for thin a and b (many rows, three columns) and a small c: one vectorised pass
/// over each column (out may be a).
template <typename Out, typename A, typename B, typename C>
void addProduct(Out&& out, const A& a, const B& b, const C& c)
{
  for (int j = 0; j < c.cols(); ++j)
    out.col(j) = a.col(j) + b.col(0) * c(0, j) + b.col(1) * c(1, j) + b.col(2) * c(2, j);
}

/// a^T b for thin a (three columns) and b: contiguous dot products of their columns.
template <int Columns, typename A, typename B>
Eigen::Matrix<double, 3, Columns> innerProduct(const A& a, const B& b)
{
  Eigen::Matrix<double, 3, Columns> product(3, b.cols());
  for (int j = 0; j < b.cols(); ++j)
    for (int i = 0; i < 3; ++i)
      product(i, j) = a.col(i).dot(b.col(j));
  return product;
}

/// solveBlockToeplitz() with the blocks stacked: a predictor's or the solution's block i is rows
/// 3 i .. 3 i + 2 of one matrix, so that each step of the recursion is a few products of long,
/// thin matrices instead of a loop over 3 x 3 products.
template <int Columns>
bool solveBlocks(const std::vector<Eigen::Matrix3d>& r, const Eigen::MatrixXd& b, Eigen::MatrixXd* x)
{
  using Eigen::Matrix3d;
  using Stack = Eigen::Matrix<double, Eigen::Dynamic, 3>;
  using Solution = Eigen::Matrix<double, Eigen::Dynamic, Columns>;
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
  // R(n-1)^T .. R(0)^T stacked: R(m+1-i)^T, i = 0..m, are consecutive blocks (n-2-m .. n-2), and
  // a sum of R(m+1-i) times a stacked block i is nine contiguous dot products.
  Stack lags(3 * n, 3);
  for (int k = 0; k < n; ++k)
    lags.middleRows<3>(3 * (n - 1 - k)) = r[k].transpose();
  // T_m forward = [P; 0 ...], forward[0] = I; T_m backward = [... 0; Q], backward[m] = I. Blocks
  // past m are zero.
  Stack forward = Stack::Zero(3 * n, 3), backward = Stack::Zero(3 * n, 3);
  Stack next_forward = Stack::Zero(3 * n, 3), next_backward = Stack::Zero(3 * n, 3);
  forward.topRows<3>() = backward.topRows<3>() = Matrix3d::Identity();
  Matrix3d p = r[0], q = r[0];
  Eigen::LLT<Matrix3d> p_llt, q_llt;
  if (!factor(q, &q_llt))
    return false;
  const int columns = static_cast<int>(b.cols());
  Solution solution = Solution::Zero(3 * n, columns);
  solution.template topRows<3>() = q_llt.solve(b.topRows<3>());
  for (int m = 0; m + 1 < n; ++m)
  {
    const int rows = 3 * (m + 1);  // blocks 0..m
    const auto lag = lags.middleRows(3 * (n - 2 - m), rows);
    // T_(m+1) [forward; 0] = [P; 0; delta], T_(m+1) [0; backward] = [delta^T; 0; Q].
    const Matrix3d delta = innerProduct<3>(lag, forward.topRows(rows));
    if (!factor(p, &p_llt))
      return false;
    const Matrix3d forward_step = q_llt.solve(delta);               // Q^-1 delta
    const Matrix3d backward_step = p_llt.solve(delta.transpose());  // P^-1 delta^T
    // forward'[i] = forward[i] - backward[i-1] Q^-1 delta, backward'[i] = backward[i-1] -
    // forward[i] P^-1 delta^T, for i = 0..m+1 (forward[m+1] = 0, backward[-1] = 0).
    next_forward.topRows<3>() = forward.topRows<3>();
    addProduct(next_forward.middleRows(3, rows), forward.middleRows(3, rows), backward.topRows(rows), -forward_step);
    next_backward.topRows<3>() = -backward_step;  // forward[0] = I
    addProduct(next_backward.middleRows(3, rows), backward.topRows(rows), forward.middleRows(3, rows), -backward_step);
    forward.swap(next_forward);
    backward.swap(next_backward);
    p -= delta.transpose() * forward_step;
    q -= delta * backward_step;
    if (!factor(q, &q_llt))
      return false;
    // T_(m+1) [x; 0] = [b_0..b_m; eta]: the new backward vector makes up the last block.
    const Block eta = innerProduct<Columns>(lag, solution.topRows(rows));
    const Block correction = q_llt.solve(b.middleRows<3>(3 * (m + 1)) - eta);
    addProduct(solution.topRows(rows + 3), solution.topRows(rows + 3), backward.topRows(rows + 3), correction);
  }
  *x = solution;
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
