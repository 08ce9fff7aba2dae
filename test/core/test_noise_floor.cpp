// NoiseFloor: the white-noise variance of a signal, whether or not spectral lines and a wave lie
// on it, against the first differences it replaces where they are inflated.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "periodic_bias_compensation/core/broadband_wave.h"
#include "periodic_bias_compensation/core/noise_floor.h"

namespace periodic_bias_compensation
{
namespace
{
struct Estimates
{
  double block_mean = 0.0;         ///< NoiseFloor's block estimates, averaged
  double first_differences = 0.0;  ///< half the mean square of first differences
};

/// White noise of standard deviation sigma at `rate`, plus a wave of 0.5 m/s^2 at 0.1 Hz and
/// vibration lines of `line` m/s^2 at 24.5 Hz and 0.39 rate, over `seconds`.
Estimates estimate(double sigma, double line, double rate, double seconds, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  NoiseFloor floor;
  Estimates out;
  int blocks = 0;
  double previous = NAN, differences = 0.0;
  const long samples = std::lround(seconds * rate);
  for (long k = 0; k < samples; ++k)
  {
    const double t = k / rate;
    const double a = 0.5 * std::sin(2.0 * M_PI * 0.1 * t) + line * std::sin(2.0 * M_PI * 24.5 * t) +
                     0.8 * line * std::sin(2.0 * M_PI * 0.39 * rate * t + 1.0) + noise(rng);
    if (floor.add(a))
    {
      out.block_mean += floor.blockVariance();
      ++blocks;
    }
    if (std::isfinite(previous))
      differences += 0.5 * (a - previous) * (a - previous);
    previous = a;
  }
  out.block_mean /= blocks;
  out.first_differences = differences / (samples - 1);
  return out;
}

TEST(NoiseFloor, WhiteNoiseAlone)
{
  for (double rate : { 10.0, 50.0, 100.0 })
  {
    const Estimates e = estimate(0.02, 0.0, rate, 600.0, 1);
    EXPECT_NEAR(e.block_mean, 4e-4, 0.08 * 4e-4) << rate << " Hz";
    // At 10 Hz the wave's own steps add half the noise to the first differences.
    if (rate >= 50.0)
    {
      EXPECT_NEAR(e.first_differences, 4e-4, 0.08 * 4e-4) << rate << " Hz";
    }
  }
}

TEST(NoiseFloor, LinesAboveTheWaveBandAreNotNoise)
{
  // The swell scenario's vertical axis: 0.1 and 0.08 m/s^2 lines on 0.02 m/s^2 of white noise.
  const Estimates e = estimate(0.02, 0.1, 100.0, 600.0, 2);
  EXPECT_GT(e.first_differences, 10.0 * 4e-4);
  EXPECT_NEAR(e.block_mean, 4e-4, 0.15 * 4e-4);
}

TEST(NoiseFloor, NonFiniteSamplesAreSkippedAndResetForgets)
{
  NoiseFloor floor;
  int completed = 0;
  for (int k = 0; k < NoiseFloor::kBlock; ++k)
    completed += floor.add(k % 2 ? NAN : 0.01 * (k % 7));
  EXPECT_EQ(completed, 0);  // half the samples were skipped
  for (int k = 0; k < NoiseFloor::kBlock / 2; ++k)
    completed += floor.add(0.01 * (k % 7));
  EXPECT_EQ(completed, 1);
  EXPECT_GT(floor.blockVariance(), 0.0);
  floor.reset();
  EXPECT_EQ(floor.blockVariance(), 0.0);
}

TEST(NoiseFloor, BroadbandWaveTakesTheLowerLevel)
{
  // 0.1 m/s^2 lines on 0.02 m/s^2 of white noise at 100 Hz: the density BroadbandWave designs
  // with is the white noise's, 2 sigma^2 / rate, not the lines'.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  BroadbandWave wave(true);
  const double rate = 100.0;
  for (long k = 0; k < 60 * 100; ++k)
  {
    const double t = k / rate;
    BroadbandWaveInput in;
    in.raw = in.offset_free = 0.1 * std::sin(2.0 * M_PI * 24.5 * t) + noise(rng);
    in.dt = k > 0 ? 1.0 / rate : 0.0;
    in.rate = rate;
    wave.update(in);
  }
  EXPECT_NEAR(wave.noiseDensitySquared(rate), 2.0 * 4e-4 / rate, 0.15 * 2.0 * 4e-4 / rate);
}

}  // namespace
}  // namespace periodic_bias_compensation
