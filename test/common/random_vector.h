// Vectors of random draws in a defined order, for the tests' own stream generators.
#pragma once

#include <Eigen/Core>

namespace periodic_bias_compensation::test
{
/// x, y and z drawn in that order. The arguments of a constructor call are evaluated in an order
/// the compiler picks (g++ right to left, clang++ left to right): Vector3(d(rng), d(rng), d(rng))
/// would give another stream under each compiler.
template <class Draw>
Eigen::Vector3d drawVector(Draw&& draw)
{
  const double x = draw();
  const double y = draw();
  const double z = draw();
  return Eigen::Vector3d(x, y, z);
}

}  // namespace periodic_bias_compensation::test
