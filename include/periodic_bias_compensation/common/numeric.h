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

/// sin(2 pi u) and cos(2 pi u) for u in [0, 1], within two units in the last place of 1: a
/// polynomial on the eighth of a turn, inline.
/// @param u fraction of a turn
/// @param s sin(2 pi u)
/// @param c cos(2 pi u)
inline void sinCosTurn(double u, double* s, double* c)
{
  // 2 pi u = q pi / 2 + t with the quadrant q = round(4 u) and |t| <= pi / 4, where the Taylor
  // series to t^15 (sine) and t^16 (cosine) are within 5e-17 of the functions.
  const double x = 4.0 * u;
  const double q = std::floor(x + 0.5);
  const double t = (x - q) * (M_PI / 2.0);  // x - q is exact
  const double z = t * t;
  const double sin_t =
      t + t * z *
              (-1.0 / 6.0 +
               z * (1.0 / 120.0 +
                    z * (-1.0 / 5040.0 +
                         z * (1.0 / 362880.0 +
                              z * (-1.0 / 39916800.0 + z * (1.0 / 6227020800.0 + z * (-1.0 / 1307674368000.0)))))));
  const double cos_t =
      1.0 +
      z * (-0.5 + z * (1.0 / 24.0 +
                       z * (-1.0 / 720.0 +
                            z * (1.0 / 40320.0 + z * (-1.0 / 3628800.0 +
                                                      z * (1.0 / 479001600.0 + z * (-1.0 / 87178291200.0 +
                                                                                    z * (1.0 / 20922789888000.0))))))));
  // sin and cos of t + q pi / 2: swapped in odd quadrants, negated by the half turn.
  const int k = static_cast<int>(q) & 3;
  const double sin_q = (k & 1) ? cos_t : sin_t;
  const double cos_q = (k & 1) ? sin_t : cos_t;
  *s = (k & 2) ? -sin_q : sin_q;
  *c = ((k + 1) & 2) ? -cos_q : cos_q;
}

/// sin(x) and cos(x) by sinCosTurn, within (2 + |x|) 2.3e-16 of them (the turn x / 2 pi is
/// rounded).
/// @param x angle [rad]
/// @param s sin(x)
/// @param c cos(x)
inline void sinCos(double x, double* s, double* c)
{
  const double u = x * (0.5 / M_PI);
  sinCosTurn(u - std::floor(u), s, c);
}
}  // namespace periodic_bias_compensation
