// DriftObserver: a constant or steadily changing bias leaves no slow-motion error, a motion well
// above 1 / drift_time_constant passes as its double integral with the observer's response, and
// the noise variances are those of the closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "periodic_bias_compensation/core/drift_observer.h"

namespace periodic_bias_compensation
{
namespace
{
constexpr double kRate = 100.0;
constexpr double kTimeConstant = 2.0;
}  // namespace

// A bias of 0.05 m/s^2 the observer was not told: it learns it, and the position returns to zero.
TEST(DriftObserver, LearnsAConstantBias)
{
  DriftObserver observer;
  const double dt = 1.0 / kRate;
  double largest = 0.0;
  for (int i = 0; i < static_cast<int>(200.0 * kRate); ++i)
  {
    observer.update(0.05, dt, kTimeConstant, true, true);
    largest = std::max(largest, std::abs(observer.position()));
  }
  EXPECT_NEAR(observer.bias(), 0.05, 1e-6);
  EXPECT_NEAR(observer.position(), 0.0, 1e-5);
  EXPECT_NEAR(observer.velocity(), 0.0, 1e-5);
  // On the way it held the position far below the 1000 m the bias integrates to in 200 s.
  EXPECT_LT(largest, 0.5);
}

// A bias changing at 1e-4 m/s^3 (a slow wander between its turns): it is followed with its rate,
// and no position error is left.
TEST(DriftObserver, FollowsABiasRampWithoutPositionError)
{
  DriftObserver observer;
  const double dt = 1.0 / kRate, rate = 1e-4;
  const int n = static_cast<int>(300.0 * kRate);
  for (int i = 0; i < n; ++i)
    observer.update(0.02 + rate * i * dt, dt, kTimeConstant, true, true);
  EXPECT_NEAR(observer.biasRate(), rate, 1e-7);
  EXPECT_NEAR(observer.bias(), 0.02 + rate * (n - 1) * dt, 1e-5);
  EXPECT_NEAR(observer.position(), 0.0, 1e-4);
}

// Without learning (before calibration) or without the bias (enable_constant off), the bias
// stays where it was set.
TEST(DriftObserver, BiasIsKeptWhenNotLearning)
{
  DriftObserver observer;
  observer.setBias(0.03);
  for (int i = 0; i < 1000; ++i)
    observer.update(0.03, 0.01, kTimeConstant, true, false);
  EXPECT_EQ(observer.bias(), 0.03);
  EXPECT_NEAR(observer.position(), 0.0, 1e-12);
  for (int i = 0; i < 1000; ++i)
    observer.update(0.03, 0.01, kTimeConstant, false, true);
  EXPECT_EQ(observer.bias(), 0.03);
  EXPECT_GT(std::abs(observer.position()), 1e-3);  // 0.03 m/s^2 now taken as motion
}

// A motion at 20 times w (a 3 s wave, drift_time_constant 10 s) passes as its double integral
// through p / a = s^2 / (s + w)^4 = (s / (s + w))^4 / s^2: gain 0.995 and a lead of
// 4 atan(w / omega) = 0.2 rad, which is the error measured, to within the Euler step's.
TEST(DriftObserver, FastMotionPassesAsItsDoubleIntegral)
{
  DriftObserver observer;
  const double time_constant = 10.0, dt = 1.0 / kRate, omega = 20.0 / time_constant, amplitude = 0.5;
  double error2 = 0.0, truth2 = 0.0;
  for (int i = 0; i < static_cast<int>(300.0 * kRate); ++i)
  {
    const double t = i * dt;
    observer.update(amplitude * std::sin(omega * t), dt, time_constant, true, true);
    if (t > 200.0)
    {
      const double truth = -amplitude / (omega * omega) * std::sin(omega * t);
      error2 += std::pow(observer.position() - truth, 2);
      truth2 += truth * truth;
    }
  }
  const std::complex<double> s(0.0, omega);
  const double expected = std::abs(1.0 - std::pow(s / (s + 1.0 / time_constant), 4));
  EXPECT_NEAR(expected, 0.2, 0.01);
  EXPECT_NEAR(std::sqrt(error2 / truth2), expected, 0.03);
}

// Steps far longer than the time constant are split: stable, the bias still learned.
TEST(DriftObserver, LongStepsAreSplitAndStable)
{
  DriftObserver observer;
  for (int i = 0; i < 200; ++i)
    observer.update(0.05, 3.0 * kTimeConstant, kTimeConstant, true, true);
  EXPECT_TRUE(std::isfinite(observer.position()));
  EXPECT_NEAR(observer.bias(), 0.05, 1e-6);
  // Beyond kMaxSteps the motion starts again at zero.
  observer.update(0.05, 1e6, 0.5, true, true);
  EXPECT_EQ(observer.position(), 0.0);
}

// White noise through the observer: the position and velocity variances of a long run agree with
// noiseVariances() within the scatter of 3000 s (about 10 %).
TEST(DriftObserver, NoiseVariancesMatchTheClosedForms)
{
  DriftObserver observer;
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  const double dt = 1.0 / kRate;
  double p2 = 0.0, v2 = 0.0;
  long count = 0;
  for (long i = 0; i < static_cast<long>(3000.0 * kRate); ++i)
  {
    observer.update(noise(random), dt, kTimeConstant, true, true);
    if (i * dt > 100.0)
    {
      p2 += observer.position() * observer.position();
      v2 += observer.velocity() * observer.velocity();
      ++count;
    }
  }
  double position = 0.0, velocity = 0.0;
  DriftObserver::noiseVariances(0.02 * 0.02, kRate, kTimeConstant, &position, &velocity);
  EXPECT_NEAR(p2 / count / position, 1.0, 0.15);
  EXPECT_NEAR(v2 / count / velocity, 1.0, 0.15);
}
}  // namespace periodic_bias_compensation
