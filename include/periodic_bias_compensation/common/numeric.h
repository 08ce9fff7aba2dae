// Small numeric helpers shared by every layer: the core, the simulator, the gap diagnosis and the
// tools. Header only and standard library only, below both cores (no allocation beyond the
// caller's vector).
#pragma once

#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

namespace periodic_bias_compensation
{
/// An angle in [-pi, pi] [rad] (std::remainder: exact, no loop).
inline double wrapAngle(double angle)
{
  return std::remainder(angle, 2.0 * M_PI);
}

/// The upper median of [first, last): its element of rank n/2, found in place (the range is
/// reordered). For a robust typical value or spread where the two middle values of an even count
/// need not be averaged. The range must not be empty.
template <typename Iterator>
double upperMedian(Iterator first, Iterator last)
{
  const Iterator middle = first + std::distance(first, last) / 2;
  std::nth_element(first, middle, last);
  return *middle;
}

/// The median: the mean of the two middle values for an even count; NaN when empty.
inline double median(std::vector<double> values)
{
  if (values.empty())
    return std::nan("");
  const auto half = values.begin() + values.size() / 2;
  const double upper = upperMedian(values.begin(), values.end());
  return values.size() % 2 == 1 ? upper : 0.5 * (upper + *std::max_element(values.begin(), half));
}
}  // namespace periodic_bias_compensation
