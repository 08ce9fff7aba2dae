// CalibrationWindow and windowOffset: the constant bias and the paper's distance bias from the
// first seconds of a record.
#include <gtest/gtest.h>

#include <cmath>

#include "periodic_bias_compensation/core/calibration_window.h"

namespace periodic_bias_compensation
{
namespace
{
constexpr double kRate = 50.0;

WindowOffsetOptions moving()
{
  WindowOffsetOptions options;
  options.rate = kRate;
  options.min_frequency = 0.05;
  options.max_frequency = 2.0;
  options.min_peak_ratio = 30.0;
  options.harmonics = 1;
  return options;
}

/// `seconds` of a bias plus a sinusoid (amplitude, frequency) at kRate.
std::vector<double> biasedSine(double seconds, double bias, double amplitude, double frequency)
{
  std::vector<double> v;
  for (long i = 0; i < static_cast<long>(seconds * kRate); ++i)
    v.push_back(bias + amplitude * std::sin(2.0 * M_PI * frequency * i / kRate + 0.7));
  return v;
}

ImuSample sampleAt(double t, const Vector3& force, bool has_orientation = false)
{
  ImuSample s;
  s.t = t;
  s.specific_force = force;
  s.has_orientation = has_orientation;
  return s;
}
}  // namespace

// 10 s of a 0.45 Hz oscillation (4.5 periods) on a bias of 0.05: its plain mean is off by tens
// of mm/s^2, the harmonic fit's constant is within 1 mm/s^2 and names the frequency.
TEST(CalibrationWindow, OffsetOfAMovingWindowIsTheFitsConstant)
{
  const std::vector<double> v = biasedSine(10.0, 0.05, 0.5, 0.45);
  FrequencyEstimate frequency;
  const double offset = windowOffset(v, moving(), &frequency);
  EXPECT_NEAR(offset, 0.05, 1e-3);
  ASSERT_TRUE(frequency.locked);
  EXPECT_NEAR(frequency.frequency, 0.45, 0.02);

  WindowOffsetOptions at_rest = moving();
  at_rest.at_rest = true;
  FrequencyEstimate none;
  const double mean = windowOffset(v, at_rest, &none);
  EXPECT_GT(std::abs(mean - 0.05), 0.02);
  EXPECT_FALSE(none.locked);
}

// At rest (noise about a bias, no peak): the mean.
TEST(CalibrationWindow, OffsetOfAWindowAtRestIsItsMean)
{
  std::vector<double> v;
  double sum = 0.0;
  for (int i = 0; i < 500; ++i)
  {
    v.push_back(-0.03 + 0.01 * std::sin(i * 1.7) * std::cos(i * 0.31));
    sum += v.back();
  }
  FrequencyEstimate frequency;
  EXPECT_NEAR(windowOffset(v, moving(), &frequency), sum / v.size(), 1e-12);
}

// The window ends once it spans the duration from its first sample; the provisional bias is the
// running mean; clear() starts a new window.
TEST(CalibrationWindow, EndsAfterItsDurationWithARunningMeanBefore)
{
  CalibrationWindow window;
  int added = 0;
  bool ended = false;
  for (; !ended && added < 1000; ++added)
  {
    const double t = 100.0 + added / kRate;
    ended = window.add(sampleAt(t, Vector3(0, 0, 9.8)), added ? 1.0 / kRate : 0.0, 10.0);
    const Vector3 provisional = window.provisionalBias(Vector3(added, 0.0, 1.0));
    EXPECT_NEAR(provisional.x(), 0.5 * added, 1e-9);
    EXPECT_NEAR(provisional.z(), 1.0, 1e-12);
  }
  EXPECT_EQ(added, 501);
  EXPECT_EQ(window.samples().size(), 501u);
  window.clear();
  EXPECT_TRUE(window.empty());
  EXPECT_FALSE(window.add(sampleAt(200.0, Vector3(0, 0, 9.8)), 0.0, 10.0));
  EXPECT_NEAR(window.provisionalBias(Vector3(3.0, 0.0, 0.0)).x(), 3.0, 1e-12);
}

// The mean specific force and whether a sample lacked an orientation; the level axes in order.
TEST(CalibrationWindow, MeanForceAndLevelAxes)
{
  CalibrationWindow window;
  window.add(sampleAt(0.0, Vector3(0.1, 0.0, 9.7), true), 0.0, 10.0);
  window.add(sampleAt(0.02, Vector3(0.3, 0.2, 9.9), true), 0.02, 10.0);
  bool any_without = true;
  const Vector3 mean = window.meanSpecificForce(&any_without);
  EXPECT_FALSE(any_without);
  EXPECT_NEAR((mean - Vector3(0.2, 0.1, 9.8)).norm(), 0.0, 1e-12);
  window.add(sampleAt(0.04, Vector3(0.2, 0.1, 9.8), false), 0.02, 10.0);
  window.meanSpecificForce(&any_without);
  EXPECT_TRUE(any_without);
  const auto axes =
      window.levelAxes([](const ImuSample& s) -> Vector3 { return s.specific_force - Vector3(0, 0, 9.8); });
  ASSERT_EQ(axes[1].size(), 3u);
  EXPECT_NEAR(axes[0][1], 0.3, 1e-12);
  EXPECT_NEAR(axes[1][2], 0.1, 1e-12);
  EXPECT_NEAR(axes[2][0], -0.1, 1e-12);
}

// The level accelerations noted as the samples came are the axes (the last sample's, not noted, is
// levelled at the end); one sample without orientation and every sample is levelled at the end,
// where its level frame is known. The window hands the noted values over and starts afresh.
TEST(CalibrationWindow, NotedLevelsAreTheAxesWhileEverySampleHasItsOrientation)
{
  const auto at_end = [](const ImuSample& s) -> Vector3 { return s.specific_force - Vector3(0, 0, 9.8); };
  CalibrationWindow window;
  window.reserve(4);
  for (int k = 0; k < 3; ++k)
  {
    window.add(sampleAt(0.02 * k, Vector3(0.1 * k, 0.0, 9.8), true), 0.02, 10.0);
    if (k < 2)
      window.noteLevel(Vector3(100.0 + k, 0.0, 0.0));  // told apart from what `at_end` gives
  }
  auto axes = window.levelAxes(at_end);
  ASSERT_EQ(axes[0].size(), 3u);
  EXPECT_EQ(axes[0][0], 100.0);
  EXPECT_EQ(axes[0][1], 101.0);
  EXPECT_NEAR(axes[0][2], 0.2, 1e-12) << "not noted: levelled at the end";

  window.clear();
  for (int k = 0; k < 3; ++k)
  {
    window.add(sampleAt(0.02 * k, Vector3(0.1 * k, 0.0, 9.8), k != 1), 0.02, 10.0);
    window.noteLevel(Vector3(100.0 + k, 0.0, 0.0));
  }
  axes = window.levelAxes(at_end);
  ASSERT_EQ(axes[0].size(), 3u);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(axes[0][k], 0.1 * k, 1e-12) << "a sample without orientation: all levelled at the end";

  window.take();
  window.add(sampleAt(1.0, Vector3(0.5, 0.0, 9.8), true), 0.0, 10.0);
  axes = window.levelAxes(at_end);
  ASSERT_EQ(axes[0].size(), 1u);
  EXPECT_NEAR(axes[0][0], 0.5, 1e-12);
  bool any_without = true;
  EXPECT_NEAR(window.meanSpecificForce(&any_without).x(), 0.5, 1e-12);
  EXPECT_FALSE(any_without) << "the sums start afresh with the window";
}

// Paper Table 1: a residual acceleration c left after the bias integrates to a velocity c t,
// whose mean over a window of T is c T / 2; none left, no drift.
TEST(CalibrationWindow, ConstantPositionDriftIsTheMeanVelocity)
{
  CalibrationWindow window;
  const double dt = 1.0 / kRate;
  for (int i = 0; i < 500; ++i)
    window.add(sampleAt(i * dt, Vector3(0.07, -0.02, 9.81)), i ? dt : 0.0, 10.0);
  const auto level = [](const ImuSample& s) -> Vector3 { return s.specific_force - Vector3(0, 0, 9.81); };
  const Vector3 bias(0.05, -0.02, 0.0);
  const Vector3 drift = window.constantPositionDrift(level, bias);
  EXPECT_NEAR(drift.x(), 0.02 * 10.0 / 2.0, 0.002);
  EXPECT_NEAR(drift.y(), 0.0, 1e-12);
  EXPECT_NEAR(drift.z(), 0.0, 1e-12);
}
}  // namespace periodic_bias_compensation
