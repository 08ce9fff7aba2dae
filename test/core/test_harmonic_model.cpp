// The harmonic model's pieces on their own: the recursive fit, its closed-form displacement,
// the window offset of a non-whole number of periods, and the signal history.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "periodic_bias_compensation/core/harmonic_model.h"

namespace periodic_bias_compensation
{
// A constant plus a fundamental and its second harmonic: the fit finds the constant, and the
// periodic part's displacement is -a_k / (k w)^2 of each component.
TEST(HarmonicModel, FitsHarmonicsAndIntegratesThemInClosedForm)
{
  const double f = 0.2, w = 2.0 * M_PI * f, rate = 50.0;
  HarmonicEstimator model;
  model.reset(2);
  double worst_position = 0.0, worst_velocity = 0.0;
  for (int i = 0; i < static_cast<int>(60.0 * rate); ++i)
  {
    const double t = i / rate, phase = w * t;
    const double a = 0.05 + 0.3 * std::cos(phase) - 0.1 * std::sin(2.0 * phase);
    model.update(phase, a, 1.0 - 1.0 / (3.0 * rate));
    if (t < 20.0)
      continue;
    double acceleration, position, velocity, variance, velocity_variance;
    model.evaluate(phase, w, &acceleration, &position, &velocity, &variance, &velocity_variance);
    const double x = -0.3 * std::cos(phase) / (w * w) + 0.1 * std::sin(2.0 * phase) / (4.0 * w * w);
    const double v = 0.3 * std::sin(phase) / w + 0.1 * std::cos(2.0 * phase) / (2.0 * w);
    worst_position = std::max(worst_position, std::abs(position - x));
    worst_velocity = std::max(worst_velocity, std::abs(velocity - v));
    EXPECT_GE(variance, 0.0);
  }
  EXPECT_NEAR(model.constant(), 0.05, 1e-9);
  EXPECT_LT(worst_position, 1e-9);
  EXPECT_LT(worst_velocity, 1e-9);
  EXPECT_EQ(model.updates(), static_cast<long>(60.0 * rate));
}

// fit() stands for the update()s it replaces: over a long stretch (36 400 samples, the rotation of
// its regressor re-anchored as it goes), over a stretch shorter than a period (the prior still
// weighs), for each number of harmonics; and updates after it continue alike. The variance
// factors come from the covariance, which the recursion carries through 36 400 rank-one updates
// and divisions by lambda: with four harmonics the two differ by 2e-7 of their value.
TEST(HarmonicModel, FitEqualsTheUpdatesItStandsFor)
{
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.02);
  const double rate = 2800.0, f = 0.077, step = 2.0 * M_PI * f / rate;
  const double lambda = std::exp(-1.0 / (rate * 3.0));
  for (int harmonics = 1; harmonics <= kMaxHarmonics; ++harmonics)
    for (int count : { 36400, 10 })
    {
      SCOPED_TRACE("harmonics " + std::to_string(harmonics) + ", count " + std::to_string(count));
      std::vector<double> values;
      for (int k = 0; k < count + 500; ++k)
      {
        const double phase = (k - count + 1) * step;
        values.push_back(0.03 + 0.4 * std::cos(phase + 0.3) - 0.15 * std::sin(2.0 * phase) +
                         0.05 * std::cos(3.0 * phase - 1.0) + noise(rng));
      }
      HarmonicEstimator updated, fitted;
      updated.reset(harmonics);
      fitted.reset(harmonics);
      for (int k = 0; k < count; ++k)
        updated.update((k - count + 1) * step, values[k], lambda);
      fitted.fit(count, -(count - 1) * step, step, lambda, [&](int k) { return values[k]; });
      EXPECT_EQ(fitted.updates(), updated.updates());
      const auto same = [&](const char* when) {
        EXPECT_NEAR(fitted.constant(), updated.constant(), 1e-9) << when;
        for (double phase : { 0.0, 1.1, -2.5 })
        {
          double a[2], x[2], v[2], variance[2], velocity_variance[2];
          updated.evaluate(phase, 2.0 * M_PI * f, &a[0], &x[0], &v[0], &variance[0], &velocity_variance[0]);
          fitted.evaluate(phase, 2.0 * M_PI * f, &a[1], &x[1], &v[1], &variance[1], &velocity_variance[1]);
          EXPECT_NEAR(a[1], a[0], 1e-9) << when;
          EXPECT_NEAR(x[1], x[0], 1e-9 * std::max(1.0, std::abs(x[0]))) << when;
          EXPECT_NEAR(v[1], v[0], 1e-9 * std::max(1.0, std::abs(v[0]))) << when;
          EXPECT_NEAR(variance[1], variance[0], 1e-6 * variance[0]) << when;
          EXPECT_NEAR(velocity_variance[1], velocity_variance[0], 1e-6 * velocity_variance[0]) << when;
        }
      };
      same("after the fit");
      for (int k = count; k < count + 500; ++k)
      {
        const double phase = (k - count + 1) * step;
        EXPECT_NEAR(fitted.update(phase, values[k], lambda), updated.update(phase, values[k], lambda), 1e-9);
      }
      same("500 updates later");
    }
}

// A 0.6 Hz oscillation over 2.3 periods: its plain mean is off by a sizeable share of the
// amplitude, the harmonic fit's constant is the offset.
TEST(HarmonicModel, WindowOffsetOfANonWholeNumberOfPeriods)
{
  const double f = 0.6, rate = 100.0, offset = 0.05;
  std::vector<double> values;
  for (int i = 0; i < static_cast<int>(2.3 / f * rate); ++i)
    values.push_back(offset + 1.4 * std::sin(2.0 * M_PI * f * i / rate + 0.3));
  double mean = 0.0;
  for (double v : values)
    mean += v / values.size();
  EXPECT_GT(std::abs(mean - offset), 0.05);
  EXPECT_NEAR(harmonicConstant(values, rate, f, 1), offset, 1e-9);
}

// ago() and midRange() against brute force on random data, with the window changed midway.
TEST(HarmonicModel, SignalHistoryMatchesBruteForce)
{
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal(0.0, 1.0);
  SignalHistory history(50);
  std::vector<double> all;
  for (int i = 0; i < 400; ++i)
  {
    all.push_back(normal(rng));
    history.push(all.back());
    EXPECT_EQ(history.size(), std::min<int>(all.size(), 50));
    EXPECT_EQ(history.ago(1), all.back());
    const int window = std::min<int>(i < 200 ? 20 : 37, history.size());
    const auto first = all.end() - window;
    const double brute = 0.5 * (*std::max_element(first, all.end()) + *std::min_element(first, all.end()));
    EXPECT_EQ(history.midRange(window), brute) << "sample " << i;
  }
  EXPECT_EQ(history.ago(50), all[all.size() - 50]);
  history.clear();
  EXPECT_EQ(history.size(), 0);
}

}  // namespace periodic_bias_compensation
