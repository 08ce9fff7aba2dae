#include "periodic_bias_compensation/core/harmonic_model.h"

#include <algorithm>

#include <Eigen/Dense>

namespace periodic_bias_compensation
{
double harmonicConstant(const std::vector<double>& values, double rate, double frequency, int harmonics)
{
  // At most 1 + 2 kMaxHarmonics unknowns: fixed-capacity matrices, no heap and no general
  // matrix product per sample.
  constexpr int kCapacity = 1 + 2 * kMaxHarmonics;
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kCapacity, kCapacity>;
  using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kCapacity, 1>;
  const int count = std::clamp(harmonics, 1, kMaxHarmonics);
  const int n = 1 + 2 * count;
  Matrix normal = Matrix::Zero(n, n);
  Column rhs = Column::Zero(n);
  Column h(n);
  for (std::size_t i = 0; i < values.size(); ++i)
  {
    const double phase = 2.0 * M_PI * frequency * i / rate;
    h[0] = 1.0;
    for (int k = 1; k <= count; ++k)
    {
      h[2 * k - 1] = std::cos(k * phase);
      h[2 * k] = std::sin(k * phase);
    }
    normal.selfadjointView<Eigen::Lower>().rankUpdate(h);
    rhs += h * values[i];
  }
  return normal.selfadjointView<Eigen::Lower>().ldlt().solve(rhs)[0];
}

}  // namespace periodic_bias_compensation
