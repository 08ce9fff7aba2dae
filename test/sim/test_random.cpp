// The random streams: the ziggurat's normal draws against the normal distribution itself
// (moments, the probability of every bin, the far tail it samples by rejection).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "periodic_bias_compensation/sim/random.h"

namespace sim = periodic_bias_compensation::sim;

namespace
{
double normalCdf(double x)
{
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}
}  // namespace

TEST(Random, NormalStreamHasTheNormalsMomentsAndTails)
{
  sim::NormalStream stream(11);
  const int n = 4000000;
  double sum = 0.0, sum2 = 0.0, sum4 = 0.0;
  int beyond3 = 0, beyond_tail = 0, beyond4 = 0;
  for (int i = 0; i < n; ++i)
  {
    const double x = stream.next();
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    beyond3 += std::abs(x) > 3.0;
    beyond_tail += std::abs(x) > 3.442619855899;  // drawn by the tail's rejection sampler
    beyond4 += std::abs(x) > 4.0;
  }
  const double mean = sum / n, var = sum2 / n - mean * mean;
  // Standard errors: 5e-4 (mean), 7e-4 (variance), 6e-3 (fourth moment, 3 for a normal).
  EXPECT_NEAR(mean, 0.0, 2.5e-3);
  EXPECT_NEAR(var, 1.0, 3.5e-3);
  EXPECT_NEAR(sum4 / n, 3.0, 0.03);
  // Expected counts 10799, 2126 and 253: within five standard deviations (Poisson).
  const auto expect_count = [n](int count, double x) {
    const double expected = 2.0 * n * normalCdf(-x);
    EXPECT_NEAR(count, expected, 5.0 * std::sqrt(expected)) << "beyond " << x;
  };
  expect_count(beyond3, 3.0);
  expect_count(beyond_tail, 3.442619855899);
  expect_count(beyond4, 4.0);
}

TEST(Random, NormalStreamFillsEveryBinAsTheDistributionDoes)
{
  // Chi-square over 160 bins of width 0.05 on [-4, 4] (they cut across the ziggurat's strips and
  // wedges) and the two tails: a strip's or wedge's share off by a percent would add ~100.
  sim::NormalStream stream(5);
  const int n = 2000000, bins = 160;
  const double lo = -4.0, width = 0.05;
  std::vector<double> count(bins + 2, 0.0);
  for (int i = 0; i < n; ++i)
  {
    const double x = stream.next();
    const int b = x < lo ? 0 : x >= -lo ? bins + 1 : 1 + static_cast<int>((x - lo) / width);
    count[b] += 1.0;
  }
  double chi2 = 0.0;
  for (int b = 0; b < bins + 2; ++b)
  {
    const double a = b == 0 ? -INFINITY : lo + (b - 1) * width;
    const double z = b == bins + 1 ? INFINITY : lo + b * width;
    const double expected = n * (normalCdf(z) - normalCdf(a));
    chi2 += (count[b] - expected) * (count[b] - expected) / expected;
  }
  // 161 degrees of freedom: mean 161, standard deviation 18; 250 is five of them above.
  EXPECT_LT(chi2, 250.0);
  EXPECT_GT(chi2, 90.0);  // not too good either: the draws are random
}

TEST(Random, NormalStreamIsTheSameForTheSameSeed)
{
  sim::NormalStream a(3), b(3), c(4);
  int differ = 0;
  for (int i = 0; i < 1000; ++i)
  {
    const double x = a.next();
    EXPECT_EQ(x, b.next());
    differ += x != c.next();
  }
  EXPECT_EQ(differ, 1000);
}
