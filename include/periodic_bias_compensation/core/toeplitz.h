// Toeplitz normal equations by Levinson's recursion (estimation core, no ROS).
//
// A causal Wiener filter of n taps solves R h = r, R the input's correlations at lags
// i - j: a Toeplitz matrix for one input, a block-Toeplitz one for several (block R(k) of the
// inputs' correlations at lag k). Levinson's recursion solves either in O(n^2) blocks where a
// general solver takes O(n^3).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace periodic_bias_compensation
{
/// Solves T x = b for the symmetric Toeplitz T with first column t. Returns false when T is not
/// positive definite to working precision.
bool solveToeplitz(const std::vector<double>& t, const std::vector<double>& b, std::vector<double>* x);
/// The same for several right-hand sides b[c] (of at least t's length) at the cost of one
/// recursion: x[c] solves T x[c] = b[c].
bool solveToeplitz(const std::vector<double>& t, const std::vector<std::vector<double>>& b,
                   std::vector<std::vector<double>>* x);

/// Solves sum_j R(i - j) x_j = b_i, i, j = 0..n-1, for three inputs: R(k) = r[k] (3 x 3) for
/// k >= 0 and R(-k) = r[k]^T (the block-Toeplitz matrix is symmetric), b and x n blocks of three
/// rows stacked (3 n rows, one column per right-hand side). Multichannel Levinson recursion
/// (Whittle's: forward and backward predictors of the three inputs). Returns false when the
/// matrix is not positive definite to working precision.
bool solveBlockToeplitz(const std::vector<Eigen::Matrix3d>& r, const Eigen::MatrixXd& b, Eigen::MatrixXd* x);

}  // namespace periodic_bias_compensation
