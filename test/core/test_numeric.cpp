// The shared numeric helpers: angle wrapping, the median and the in-place upper median.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "periodic_bias_compensation/common/numeric.h"

namespace pbc = periodic_bias_compensation;

TEST(Numeric, WrapAngleKeepsTheAngleWithinPlusMinusPi)
{
  EXPECT_DOUBLE_EQ(pbc::wrapAngle(0.5), 0.5);
  EXPECT_NEAR(pbc::wrapAngle(0.5 + 6.0 * M_PI), 0.5, 1e-12);
  EXPECT_NEAR(pbc::wrapAngle(-0.5 - 4.0 * M_PI), -0.5, 1e-12);
  EXPECT_NEAR(pbc::wrapAngle(3.5), 3.5 - 2.0 * M_PI, 1e-15);
  EXPECT_NEAR(pbc::wrapAngle(-3.5), 2.0 * M_PI - 3.5, 1e-15);
  for (double a = -50.0; a <= 50.0; a += 0.37)
  {
    const double w = pbc::wrapAngle(a);
    EXPECT_LE(std::abs(w), M_PI) << a;
    EXPECT_NEAR(std::remainder(a - w, 2.0 * M_PI), 0.0, 1e-12) << a;
  }
}

TEST(Numeric, MedianAveragesTheTwoMiddleValuesOfAnEvenCount)
{
  EXPECT_DOUBLE_EQ(pbc::median({ 5.0, 1.0, 3.0 }), 3.0);
  EXPECT_DOUBLE_EQ(pbc::median({ 4.0, 1.0, 3.0, 2.0 }), 2.5);
  EXPECT_DOUBLE_EQ(pbc::median({ 7.0 }), 7.0);
  EXPECT_TRUE(std::isnan(pbc::median({})));
}

TEST(Numeric, UpperMedianIsTheElementOfRankHalfTheCount)
{
  std::vector<double> odd{ 9.0, 2.0, 7.0, 4.0, 5.0 };
  EXPECT_DOUBLE_EQ(pbc::upperMedian(odd.begin(), odd.end()), 5.0);
  std::vector<double> even{ 4.0, 1.0, 3.0, 2.0 };
  EXPECT_DOUBLE_EQ(pbc::upperMedian(even.begin(), even.end()), 3.0);
  // In place: the range is reordered around its middle, nothing is allocated.
  EXPECT_LE(even[0], 3.0);
  EXPECT_LE(even[1], 3.0);
  EXPECT_DOUBLE_EQ(even[2], 3.0);
}
