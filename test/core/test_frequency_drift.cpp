// FrequencyDrift: a steadily drifting frequency is extrapolated to now; scatter alone, growing
// windows and absurd slopes are not.
#include <gtest/gtest.h>

#include <random>

#include "periodic_bias_compensation/core/frequency_drift.h"

namespace periodic_bias_compensation
{
namespace
{
constexpr double kSpan = 60.0;  // FFT window [s]
constexpr double kHop = 1.0;    // between estimates [s]

/// Estimates every hop from t0 to t1 of a frequency f(centre time) with Gaussian scatter.
template <class F>
void feed(FrequencyDrift* drift, double t0, double t1, F f, double scatter, unsigned seed = 3)
{
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, scatter);
  for (double now = t0; now <= t1; now += kHop)
    drift->add(now, f(now - 0.5 * kSpan) + noise(random), kSpan, true, kHop);
}
}  // namespace

// An encounter frequency rising by 1 mHz/s (a turn into the waves): the slope is found, and the
// newest estimate, 30 s old at its window's centre, is carried to now.
TEST(FrequencyDrift, ASteadyDriftIsExtrapolatedToNow)
{
  FrequencyDrift drift;
  const auto f = [](double t) { return 0.5 + 1e-3 * (t - 100.0); };
  feed(&drift, 100.0, 130.0, f, 2e-4);
  EXPECT_NEAR(drift.slope(), 1e-3, 1e-4);
  const double newest = f(130.0 - 0.5 * kSpan);
  EXPECT_NEAR(drift.at(130.0, newest, 0.05), f(130.0), 0.003);
}

// The same scatter without a drift: no slope stands out of it, the estimate is used as it is.
TEST(FrequencyDrift, ScatterAloneIsNoDrift)
{
  FrequencyDrift drift;
  int believed = 0;
  for (unsigned seed = 1; seed <= 20; ++seed)
  {
    drift.clear();
    feed(
        &drift, 100.0, 130.0, [](double) { return 0.1; }, 2e-4, seed);
    believed += drift.slope() != 0.0 ? 1 : 0;
  }
  EXPECT_LE(believed, 1);
  drift.clear();
  EXPECT_EQ(drift.at(500.0, 0.1, 0.05), 0.1);
}

// While the window still grows, its estimates do not enter (and the history starts over), and a
// new lock (clear) forgets the slope.
TEST(FrequencyDrift, GrowingWindowsAndNewLocksGiveNoSlope)
{
  FrequencyDrift drift;
  feed(
      &drift, 100.0, 130.0, [](double t) { return 0.1 + 1e-3 * t; }, 0.0);
  ASSERT_GT(drift.slope(), 0.0);
  drift.add(131.0, 0.3, 20.0, false, kHop);
  EXPECT_EQ(drift.slope(), 0.0);
  feed(
      &drift, 140.0, 170.0, [](double t) { return 0.1 + 1e-3 * t; }, 0.0);
  ASSERT_GT(drift.slope(), 0.0);
  drift.clear();
  EXPECT_EQ(drift.slope(), 0.0);
}

// A slope beyond kMaxSlope is bounded, and the extrapolation stays within kMaxExtrapolation of
// the estimate and above the band's lower edge.
TEST(FrequencyDrift, SlopeAndExtrapolationAreBounded)
{
  FrequencyDrift drift;
  feed(
      &drift, 100.0, 130.0, [](double t) { return 1.0 - 0.05 * (t - 50.0); }, 0.0);
  EXPECT_EQ(drift.slope(), -FrequencyDrift::kMaxSlope);
  EXPECT_NEAR(drift.at(1000.0, 0.2, 0.05), 0.2 * (1.0 - FrequencyDrift::kMaxExtrapolation), 1e-12);
  EXPECT_NEAR(drift.at(1000.0, 0.055, 0.05), 0.05, 1e-12);
  EXPECT_NEAR(drift.at(-1000.0, 0.2, 0.05), 0.2 * (1.0 + FrequencyDrift::kMaxExtrapolation), 1e-12);
}
}  // namespace periodic_bias_compensation
