#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "periodic_bias_compensation/core/time_base.h"

namespace pbc = periodic_bias_compensation;
using pbc::StampVerdict;
using pbc::TimeBase;

namespace
{
struct Tally
{
  int accepted = 0, duplicate = 0, early = 0, held = 0, restart = 0, gap = 0;
};

Tally feed(TimeBase& base, const std::vector<double>& stamps)
{
  Tally tally;
  for (double t : stamps)
    switch (base.update(t))
    {
      case StampVerdict::kAccept:
        ++tally.accepted;
        break;
      case StampVerdict::kDuplicate:
        ++tally.duplicate;
        break;
      case StampVerdict::kEarly:
        ++tally.early;
        break;
      case StampVerdict::kHeld:
        ++tally.held;
        break;
      case StampVerdict::kRestart:
        ++tally.restart;
        break;
      case StampVerdict::kGap:
        ++tally.gap;
        break;
    }
  return tally;
}

/// n stamps at `rate` from t0, each moved by uniform jitter of +-jitter periods.
std::vector<double> stream(double t0, double rate, int n, double jitter = 0.0, unsigned seed = 1)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-jitter, jitter);
  std::vector<double> stamps;
  for (int k = 0; k < n; ++k)
    stamps.push_back(t0 + (k + (jitter > 0.0 ? uniform(rng) : 0.0)) / rate);
  return stamps;
}
}  // namespace

TEST(TimeBase, ExactStreamGivesItsPeriodAndSteps)
{
  TimeBase base;
  const auto stamps = stream(1.7e9, 50.0, 3000);
  const Tally tally = feed(base, stamps);
  EXPECT_EQ(tally.accepted, 3000);
  EXPECT_NEAR(base.rate(), 50.0, 1e-6);
  EXPECT_NEAR(base.step(), 0.02, 1e-9);
  EXPECT_EQ(base.glitches(), 0u);
  EXPECT_EQ(base.rateChanges(), 0u);
}

TEST(TimeBase, JitterOfAQuarterPeriodIsNeitherARestartNorARateChange)
{
  // Uniform jitter of +-25 % of the period on every stamp, 10 min at 50 Hz; and a publisher's
  // delays (exponential, mean 15 % of a period: one in 750 stamps more than a period late) on a
  // 100 Hz stream.
  for (unsigned seed : { 1u, 2u, 3u })
  {
    TimeBase base;
    const Tally tally = feed(base, stream(100.0, 50.0, 30000, 0.25, seed));
    EXPECT_EQ(tally.accepted, 30000);
    EXPECT_EQ(tally.early + tally.held + tally.restart + tally.gap, 0);
    EXPECT_EQ(base.rateChanges(), 0u);
    EXPECT_NEAR(base.rate(), 50.0, 0.05) << "seed " << seed;
    // The step is the period, not the jittered difference.
    EXPECT_NEAR(base.step(), 0.02, 1e-4);
  }
  std::mt19937_64 rng(7);
  std::exponential_distribution<double> delay(1.0 / 0.0015);
  std::vector<double> stamps;
  for (int k = 0; k < 12000; ++k)
    stamps.push_back(5.0 + k * 0.01 + delay(rng));
  TimeBase base;
  const Tally tally = feed(base, stamps);
  EXPECT_EQ(tally.restart + tally.gap, 0);
  EXPECT_EQ(base.rateChanges(), 0u);
  EXPECT_NEAR(base.rate(), 100.0, 0.5);
}

TEST(TimeBase, LoneGlitchesAreDroppedAndCountedNeverARestart)
{
  // Each glitch alone in an exact 50 Hz stream: a stamp 5 s in the past, a stamp of 0, one 5 s in
  // the future, a duplicate, one 1 ms after its predecessor.
  struct Glitch
  {
    const char* name;
    double stamp;  // replaces sample 1000's stamp
    StampVerdict verdict;
  };
  const double t0 = 1000.0;
  const auto clean = stream(t0, 50.0, 2000);
  for (const Glitch& g : { Glitch{ "5 s in the past", clean[1000] - 5.0, StampVerdict::kHeld },
                           Glitch{ "stamped 0", 0.0, StampVerdict::kHeld },
                           Glitch{ "5 s in the future", clean[1000] + 5.0, StampVerdict::kHeld },
                           Glitch{ "duplicated", clean[999], StampVerdict::kDuplicate },
                           Glitch{ "1 ms after its predecessor", clean[999] + 0.001, StampVerdict::kEarly } })
  {
    TimeBase base;
    std::vector<double> stamps = clean;
    stamps[1000] = g.stamp;
    for (std::size_t k = 0; k < stamps.size(); ++k)
    {
      const StampVerdict v = base.update(stamps[k]);
      if (k == 1000)
      {
        EXPECT_EQ(v, g.verdict) << g.name;
      }
      else
      {
        ASSERT_EQ(v, StampVerdict::kAccept) << g.name << " at sample " << k;
      }
      if (k == 1001)
      {
        EXPECT_NEAR(base.step(), 0.04, 1e-9) << g.name << ": the dropped sample is stepped over";
      }
    }
    EXPECT_EQ(base.glitches(), g.verdict == StampVerdict::kDuplicate ? 0u : 1u) << g.name;
    EXPECT_EQ(base.rateChanges(), 0u) << g.name;
    EXPECT_NEAR(base.rate(), 50.0, 1e-6) << g.name;
  }
}

TEST(TimeBase, SustainedJumpsAreConfirmedOnTheirFifthSample)
{
  // A bag replayed again (stamps back by 30 s) and a gap of 2 s: held until kConfirmSamples
  // samples continue the jump, then a restart or a gap whose held samples start the record.
  for (double jump : { -30.0, 2.0 })
  {
    TimeBase base;
    auto stamps = stream(10.0, 100.0, 500);
    const double resume = stamps.back() + jump;
    for (double t : stamps)
      ASSERT_EQ(base.update(t), StampVerdict::kAccept);
    for (int k = 0; k < pbc::kConfirmSamples - 1; ++k)
      EXPECT_EQ(base.update(resume + k * 0.01), StampVerdict::kHeld);
    EXPECT_EQ(base.update(resume + (pbc::kConfirmSamples - 1) * 0.01),
              jump < 0 ? StampVerdict::kRestart : StampVerdict::kGap);
    EXPECT_EQ(base.heldCount(), pbc::kConfirmSamples);
    EXPECT_DOUBLE_EQ(base.heldStep(0), 0.0);
    EXPECT_NEAR(base.heldStep(1), 0.01, 1e-9);
    EXPECT_EQ(base.glitches(), 0u);
    EXPECT_EQ(base.update(resume + pbc::kConfirmSamples * 0.01), StampVerdict::kAccept);
    EXPECT_NEAR(base.step(), 0.01, 1e-9);
    EXPECT_NEAR(base.rate(), 100.0, 1e-6);
  }
}

TEST(TimeBase, GenuineRateChangesAreFollowedWithinTenSeconds)
{
  // 10 Hz for 30 s, 1000 Hz for 20 s, 50 Hz for 30 s, with 10 % jitter: the rate within 0.5 %
  // 10 s after each change, one change counted for each, nothing taken for a restart.
  std::vector<std::pair<double, double>> legs{ { 10.0, 30.0 }, { 1000.0, 20.0 }, { 50.0, 30.0 } };
  TimeBase base;
  double t = 100.0;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  Tally total;
  for (const auto& [rate, duration] : legs)
  {
    const double start = t;
    while (t < start + duration)
    {
      const Tally tally = feed(base, { t + jitter(rng) / rate });
      total.restart += tally.restart;
      total.gap += tally.gap;
      total.held += tally.held;
      t += 1.0 / rate;
      if (t > start + 10.0 && t < start + 10.0 + 1.0 / rate)
      {
        EXPECT_NEAR(base.rate(), rate, 0.005 * rate) << "10 s after the change to " << rate << " Hz";
      }
    }
    EXPECT_NEAR(base.rate(), rate, 0.005 * rate);
  }
  EXPECT_EQ(total.restart + total.gap + total.held, 0);
  EXPECT_EQ(base.rateChanges(), 2u);
}

TEST(TimeBase, ShortGapsAreSteppedOverAsWholePeriods)
{
  TimeBase base;
  auto stamps = stream(0.0, 100.0, 1000);
  stamps.erase(stamps.begin() + 500, stamps.begin() + 510);  // ten samples lost (0.1 s)
  for (std::size_t k = 0; k < stamps.size(); ++k)
  {
    ASSERT_EQ(base.update(stamps[k]), StampVerdict::kAccept);
    if (k == 500)
    {
      EXPECT_NEAR(base.step(), 0.11, 1e-9);
    }
  }
  EXPECT_NEAR(base.rate(), 100.0, 1e-6);
}
