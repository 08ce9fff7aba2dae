// TurnDetector: a turn restarts the spectrum record and holds the horizontal share off for long;
// the yaw a sea induces does neither.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "periodic_bias_compensation/core/turn_detector.h"

namespace periodic_bias_compensation
{
namespace
{
constexpr double kRate = 50.0;

/// What a run of the detector did: turns seen, and the share's state over time.
struct ShareRecord
{
  int turns = 0;
  double allowed_time = 0.0;      ///< total time the share was allowed [s]
  double first_allowed = -1.0;    ///< first time it was allowed [s]
  double first_forbidden = -1.0;  ///< first time it was not [s]
  double last_forbidden = -1.0;   ///< last time it was not [s]
  double manoeuvre_time = 0.0;    ///< total time the records took a manoeuvre [s]
};

/// Feeds `seconds` of the heading `heading(t)` [rad, unwrapped] with its rate by difference.
ShareRecord feed(TurnDetector* detector, double seconds, const std::function<double(double)>& heading,
                 bool attitude_measured = true, double t0 = 0.0)
{
  ShareRecord run;
  const double dt = 1.0 / kRate;
  for (long i = 0; i < static_cast<long>(seconds * kRate); ++i)
  {
    const double t = t0 + i * dt;
    const double yaw_rate = (heading(t + 0.5 * dt) - heading(t - 0.5 * dt)) / dt;
    detector->update(std::remainder(heading(t), 2.0 * M_PI), yaw_rate, i == 0 && t0 == 0.0 ? 0.0 : dt,
                     attitude_measured);
    run.turns += detector->turned() ? 1 : 0;
    run.manoeuvre_time += detector->recordManoeuvre() ? dt : 0.0;
    if (detector->horizontalShareAllowed())
    {
      run.allowed_time += dt;
      if (run.first_allowed < 0.0)
        run.first_allowed = t;
    }
    else
    {
      if (run.first_forbidden < 0.0)
        run.first_forbidden = t;
      run.last_forbidden = t;
    }
  }
  return run;
}
}  // namespace

TEST(TurnDetector, HeadingOfAnAttitudeIsItsYaw)
{
  const Eigen::Quaterniond q = Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX());
  EXPECT_NEAR(headingOf(q), 2.5, 1e-12);
  EXPECT_NEAR(headingOf(Eigen::Quaterniond(Eigen::AngleAxisd(-3.0, Eigen::Vector3d::UnitZ()))), -3.0, 1e-12);
}

// A moored buoy yawing 0.3 rad at 10 s about a heading across the +-pi seam: no turn, no
// manoeuvre of the records, and the share held off only while the sea's spread is first measured
// (within the first minute).
TEST(TurnDetector, YawOfTheSeaIsNoTurn)
{
  TurnDetector detector;
  const ShareRecord run = feed(&detector, 900.0, [](double t) { return M_PI + 0.3 * std::sin(2.0 * M_PI * 0.1 * t); });
  EXPECT_EQ(run.turns, 0);
  EXPECT_EQ(run.manoeuvre_time, 0.0);
  EXPECT_GE(run.first_forbidden, 0.0) << "held while the spread is measured";
  EXPECT_LT(run.last_forbidden, 60.0);
}

// A 90 degree turn at 0.03 rad/s after 300 s of steady heading: it is told as a turn (more than
// once: every kRecordTurn of the mean), the share goes off at its start and stays off kAfterTurn
// after its end.
TEST(TurnDetector, ATurnHoldsTheShareOffLong)
{
  TurnDetector detector;
  const double start = 300.0, rate = 0.03, length = 0.5 * M_PI / rate;
  const auto heading = [&](double t) { return 0.4 + rate * std::clamp(t - start, 0.0, length); };
  const ShareRecord before = feed(&detector, start, heading);
  EXPECT_EQ(before.turns, 0);
  EXPECT_TRUE(detector.horizontalShareAllowed());
  const ShareRecord after = feed(&detector, 600.0, heading, true, start);
  EXPECT_GE(after.turns, 3);
  EXPECT_LE(after.turns, 5);
  // The 2 s mean rate passes kTurnRate within a second of the start.
  EXPECT_GE(after.first_forbidden, start);
  EXPECT_LT(after.first_forbidden, start + 1.0);
  EXPECT_GT(after.last_forbidden, start + length + TurnDetector::kAfterTurn - 1.0);
  EXPECT_LT(after.last_forbidden, start + length + TurnDetector::kAfterTurn + 15.0);
}

// A lone yaw of 0.1 rad in 2 s (a gust) on an otherwise steady heading: beyond kTurnRate, no
// heading change of kRecordTurn: the share is off for about kAfterYaw, not kAfterTurn.
TEST(TurnDetector, ALoneYawHoldsTheShareOffBriefly)
{
  TurnDetector detector;
  const auto heading = [](double t) { return t < 400.0 ? 0.0 : 0.1 * std::min(1.0, (t - 400.0) / 2.0); };
  feed(&detector, 400.0, heading);
  ASSERT_TRUE(detector.horizontalShareAllowed());
  const ShareRecord run = feed(&detector, 200.0, heading, true, 400.0);
  EXPECT_EQ(run.turns, 0);
  EXPECT_GT(run.last_forbidden, 400.0 + TurnDetector::kAfterYaw);
  EXPECT_LT(run.last_forbidden, 400.0 + 4.0 * TurnDetector::kAfterYaw);
}

// One level frame (no measured attitude): the share is never allowed, whatever the heading does.
TEST(TurnDetector, NoAttitudeNoShare)
{
  TurnDetector detector;
  const ShareRecord run = feed(
      &detector, 600.0, [](double) { return 1.0; }, false);
  EXPECT_EQ(run.allowed_time, 0.0);
}

// A steady heading allows the share kAfterYaw after the first sample (the yaw rate's mean starts
// there); reset() forgets a turn's hold.
TEST(TurnDetector, ResetForgetsATurn)
{
  TurnDetector detector;
  const auto heading = [](double t) { return 0.03 * std::min(t, 50.0); };
  const ShareRecord steady = feed(&detector, 200.0, [](double) { return 0.0; });
  EXPECT_NEAR(steady.first_allowed, TurnDetector::kAfterYaw, 0.05);
  EXPECT_LT(steady.last_forbidden, TurnDetector::kAfterYaw);
  feed(&detector, 60.0, heading, true, 200.0);
  ASSERT_FALSE(detector.horizontalShareAllowed());
  detector.reset();
  const ShareRecord run = feed(&detector, 10.0, [](double) { return 1.5; });
  EXPECT_EQ(run.turns, 0);
  EXPECT_NEAR(run.first_allowed, TurnDetector::kAfterYaw, 0.05);
  EXPECT_LT(run.last_forbidden, TurnDetector::kAfterYaw);
}

// sinceYaw() counts from the last sample beyond the turn rate, with or without a measured
// attitude: large before any yaw, zero while the ship turns, then the time since the turn ended
// (the 2 s mean rate falls below kTurnRate within a few seconds of it).
TEST(TurnDetector, SinceYawCountsFromTheLastYaw)
{
  for (const bool attitude_measured : { true, false })
  {
    TurnDetector detector;
    const double start = 200.0, rate = 0.03, length = 0.5 * M_PI / rate;
    const auto heading = [&](double t) { return rate * std::clamp(t - start, 0.0, length); };
    feed(&detector, start, heading, attitude_measured);
    EXPECT_GT(detector.sinceYaw(), start - 1.0);
    feed(&detector, 10.0, heading, attitude_measured, start);
    EXPECT_EQ(detector.sinceYaw(), 0.0);
    feed(&detector, length - 10.0 + 30.0, heading, attitude_measured, start + 10.0);
    EXPECT_GT(detector.sinceYaw(), 30.0 - 4.0 * TurnDetector::kTurnAveraging);
    EXPECT_LT(detector.sinceYaw(), 30.0);
  }
}

// The sea's yaw holds the share off but is no manoeuvre of the records; a turn until kAfterTurn
// after it, and a missing attitude, are.
TEST(TurnDetector, RecordManoeuvresAreTurnsAndMissingAttitudes)
{
  TurnDetector yawing;
  const ShareRecord yaw = feed(&yawing, 30.0, [](double t) { return 0.1 * std::sin(0.8 * t); });
  EXPECT_GT(yaw.allowed_time, 0.0);
  EXPECT_LT(yaw.allowed_time, 30.0) << "held while the spread is measured";
  EXPECT_EQ(yaw.manoeuvre_time, 0.0);

  TurnDetector blind;
  const ShareRecord dark = feed(
      &blind, 30.0, [](double) { return 0.3; }, false);
  EXPECT_NEAR(dark.manoeuvre_time, 30.0, 0.1);

  TurnDetector turning;
  const auto heading = [](double t) { return t < 300.0 ? 0.0 : 0.03 * std::min(t - 300.0, 50.0); };
  feed(&turning, 300.0, heading);
  ASSERT_FALSE(turning.recordManoeuvre());
  feed(&turning, 60.0, heading, true, 300.0);
  EXPECT_TRUE(turning.recordManoeuvre());
  feed(&turning, 0.9 * TurnDetector::kAfterTurn, heading, true, 360.0);
  EXPECT_TRUE(turning.recordManoeuvre());
  feed(&turning, 0.2 * TurnDetector::kAfterTurn, heading, true, 360.0 + 0.9 * TurnDetector::kAfterTurn);
  EXPECT_FALSE(turning.recordManoeuvre());
}

}  // namespace periodic_bias_compensation
