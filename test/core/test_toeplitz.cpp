// Levinson's recursion for the Toeplitz normal equations, one input and three, against a general
// dense solve of the same matrices.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <Eigen/Dense>

#include "periodic_bias_compensation/core/toeplitz.h"

namespace pbc = periodic_bias_compensation;

namespace
{
/// Correlations at lags 0..n-1 of three inputs made by a random moving average of white noise
/// (a positive definite block-Toeplitz matrix when the noise's own covariance is): R(k) =
/// sum_j C_(j+k) C_j^T, plus `white` on R(0).
std::vector<Eigen::Matrix3d> movingAverageCorrelations(int n, int order, double white, unsigned seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Matrix3d> c(order);
  for (Eigen::Matrix3d& m : c)
    m = Eigen::Matrix3d::NullaryExpr([&]() { return normal(rng); });
  std::vector<Eigen::Matrix3d> r(n, Eigen::Matrix3d::Zero());
  for (int k = 0; k < n; ++k)
    for (int j = 0; j + k < order; ++j)
      r[k] += c[j + k] * c[j].transpose();
  r[0] += white * Eigen::Matrix3d::Identity();
  return r;
}

Eigen::MatrixXd dense(const std::vector<Eigen::Matrix3d>& r)
{
  const int n = static_cast<int>(r.size());
  Eigen::MatrixXd t(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      t.block<3, 3>(3 * i, 3 * j) = i >= j ? r[i - j] : Eigen::Matrix3d(r[j - i].transpose());
  return t;
}
}  // namespace

TEST(Toeplitz, ScalarLevinsonMatchesADenseSolve)
{
  const int n = 50;
  std::vector<double> t(n), b(n);
  for (int k = 0; k < n; ++k)
  {
    t[k] = std::exp(-0.1 * k) * std::cos(0.7 * k) + (k == 0 ? 0.1 : 0.0);
    b[k] = std::sin(0.3 * k);
  }
  Eigen::MatrixXd dense_t(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      dense_t(i, j) = t[std::abs(i - j)];
  const Eigen::VectorXd expected = dense_t.ldlt().solve(Eigen::Map<Eigen::VectorXd>(b.data(), n));
  std::vector<double> x;
  ASSERT_TRUE(pbc::solveToeplitz(t, b, &x));
  for (int i = 0; i < n; ++i)
    EXPECT_NEAR(x[i], expected[i], 1e-9 * expected.cwiseAbs().maxCoeff()) << i;
}

TEST(Toeplitz, SeveralRightHandSidesSolveAsEachAlone)
{
  const int n = 60;
  std::vector<double> t(n), first(n), second(n);
  for (int k = 0; k < n; ++k)
  {
    t[k] = std::exp(-0.05 * k) * std::cos(0.4 * k) + (k == 0 ? 0.2 : 0.0);
    first[k] = std::sin(0.3 * k);
    second[k] = std::cos(0.11 * k) - 0.5;
  }
  std::vector<std::vector<double>> both;
  ASSERT_TRUE(pbc::solveToeplitz(t, { first, second }, &both));
  ASSERT_EQ(both.size(), 2u);
  std::vector<double> alone;
  for (int c = 0; c < 2; ++c)
  {
    ASSERT_TRUE(pbc::solveToeplitz(t, c == 0 ? first : second, &alone));
    ASSERT_EQ(both[c].size(), alone.size());
    for (int i = 0; i < n; ++i)
      EXPECT_EQ(both[c][i], alone[i]) << "right-hand side " << c << ", tap " << i;
  }
  // A right-hand side shorter than the matrix is refused.
  EXPECT_FALSE(pbc::solveToeplitz(t, { first, std::vector<double>(n - 1, 1.0) }, &both));
}

TEST(Toeplitz, BlockLevinsonMatchesADenseSolve)
{
  // Asymmetric blocks (R(k) != R(k)^T): the inputs lead and lag each other.
  for (unsigned seed = 1; seed <= 4; ++seed)
  {
    const int n = 40;
    const std::vector<Eigen::Matrix3d> r = movingAverageCorrelations(n, 12, 0.05, seed);
    ASSERT_GT((r[3] - r[3].transpose()).norm(), 0.1 * r[3].norm());
    const Eigen::MatrixXd t = dense(r);
    std::mt19937 rng(100 + seed);
    std::normal_distribution<double> normal;
    const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(3 * n, 2, [&]() { return normal(rng); });
    const Eigen::MatrixXd expected = t.ldlt().solve(b);
    Eigen::MatrixXd x;
    ASSERT_TRUE(pbc::solveBlockToeplitz(r, b, &x)) << seed;
    ASSERT_EQ(x.rows(), 3 * n);
    ASSERT_EQ(x.cols(), 2);
    EXPECT_LT((x - expected).norm(), 1e-8 * expected.norm()) << seed;
    EXPECT_LT((t * x - b).norm(), 1e-9 * b.norm()) << seed;
  }
}

TEST(Toeplitz, BlockLevinsonOfOneInputIsTheScalarOne)
{
  // Inputs 2 and 3 unrelated white noise: input 1's taps are the scalar solution.
  const int n = 30;
  std::vector<double> t(n), b(n);
  std::vector<Eigen::Matrix3d> r(n, Eigen::Matrix3d::Zero());
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(3 * n, 1);
  for (int k = 0; k < n; ++k)
  {
    t[k] = std::exp(-0.05 * k) * std::cos(0.4 * k) + (k == 0 ? 0.2 : 0.0);
    b[k] = std::cos(0.2 * k);
    r[k](0, 0) = t[k];
    rhs(3 * k, 0) = b[k];
  }
  r[0](1, 1) = r[0](2, 2) = 1.0;
  std::vector<double> scalar;
  Eigen::MatrixXd x;
  ASSERT_TRUE(pbc::solveToeplitz(t, b, &scalar));
  ASSERT_TRUE(pbc::solveBlockToeplitz(r, rhs, &x));
  for (int k = 0; k < n; ++k)
  {
    EXPECT_NEAR(x(3 * k, 0), scalar[k], 1e-9) << k;
    EXPECT_EQ(x(3 * k + 1, 0), 0.0);
    EXPECT_EQ(x(3 * k + 2, 0), 0.0);
  }
}

TEST(Toeplitz, NotPositiveDefiniteIsRefused)
{
  // Two inputs that are one (a singular matrix), and correlations that no process has.
  const int n = 10;
  std::vector<Eigen::Matrix3d> singular(n, Eigen::Matrix3d::Zero());
  for (int k = 0; k < n; ++k)
    singular[k] = std::pow(0.5, k) * Eigen::Matrix3d::Ones();
  Eigen::MatrixXd x;
  EXPECT_FALSE(pbc::solveBlockToeplitz(singular, Eigen::MatrixXd::Ones(3 * n, 1), &x));
  std::vector<Eigen::Matrix3d> impossible(n, Eigen::Matrix3d::Zero());
  impossible[0] = Eigen::Matrix3d::Identity();
  impossible[1] = 2.0 * Eigen::Matrix3d::Identity();
  EXPECT_FALSE(pbc::solveBlockToeplitz(impossible, Eigen::MatrixXd::Ones(3 * n, 1), &x));
  EXPECT_FALSE(pbc::solveBlockToeplitz({}, Eigen::MatrixXd(), &x));
  EXPECT_FALSE(pbc::solveBlockToeplitz(impossible, Eigen::MatrixXd::Ones(3, 1), &x));  // b's size
  std::vector<double> scalar;
  EXPECT_FALSE(pbc::solveToeplitz({ 1.0, 2.0, 0.0 }, { 1.0, 1.0, 1.0 }, &scalar));
}
