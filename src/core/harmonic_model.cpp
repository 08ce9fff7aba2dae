#include "periodic_bias_compensation/core/harmonic_model.h"

#include <Eigen/Dense>

namespace periodic_bias_compensation
{
double harmonicConstant(const std::vector<double>& values, double rate, double frequency, int harmonics)
{
  const int n = 1 + 2 * harmonics;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd h(n);
  for (std::size_t i = 0; i < values.size(); ++i)
  {
    const double phase = 2.0 * M_PI * frequency * i / rate;
    h[0] = 1.0;
    for (int k = 1; k <= harmonics; ++k)
    {
      h[2 * k - 1] = std::cos(k * phase);
      h[2 * k] = std::sin(k * phase);
    }
    normal.noalias() += h * h.transpose();
    rhs.noalias() += h * values[i];
  }
  return normal.ldlt().solve(rhs)[0];
}

}  // namespace periodic_bias_compensation
