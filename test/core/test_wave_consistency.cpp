// WaveConsistency: a wave output that the measured acceleration shows is left alone, one that
// goes on after the motion has stopped fades out, smoothly, whatever the bias does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "../common/test_size.h"
#include "periodic_bias_compensation/core/wave_consistency.h"

namespace periodic_bias_compensation
{
namespace
{
struct Component
{
  double omega, amplitude, phase;  ///< [rad/s], acceleration [m/s^2], [rad]
};

/// A broad sea's acceleration: `count` components with periods between `shortest` and
/// `longest` [s] and an acceleration RMS of `rms` [m/s^2].
std::vector<Component> sea(int count, double shortest, double longest, double rms, std::mt19937_64* rng)
{
  std::uniform_real_distribution<double> period(shortest, longest), phase(0.0, 2.0 * M_PI);
  std::vector<Component> out;
  for (int k = 0; k < count; ++k)
    out.push_back({ 2.0 * M_PI / period(*rng), rms * std::sqrt(2.0 / count), phase(*rng) });
  return out;
}

double acceleration(const std::vector<Component>& c, double t)
{
  double a = 0.0;
  for (const Component& k : c)
    a += k.amplitude * std::sin(k.omega * t + k.phase);
  return a;
}

/// The velocity whose derivative is acceleration(c, t).
double velocity(const std::vector<Component>& c, double t)
{
  double v = 0.0;
  for (const Component& k : c)
    v -= k.amplitude / k.omega * std::cos(k.omega * t + k.phase);
  return v;
}

struct Trace
{
  double min_weight = 1.0;
  std::vector<double> weights;
};

/// Feeds `seconds` at `rate`: measured = the sea while t < stop, then nothing, plus white noise of
/// density `noise` [m/s^2/sqrt(Hz)], a constant offset and a bias random walk of `walk`
/// [m/s^2/sqrt(s)]; the output's velocity is `gain` times the sea's `lag` [s] before, stop or not.
Trace feed(const std::vector<Component>& c, double rate, double seconds, double stop, double noise, double walk,
           double gain, unsigned seed, double lag = 0.0)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  WaveConsistency check;
  Trace r;
  double bias = 0.08;
  const double dt = 1.0 / rate;
  for (long k = 0; k < std::lround(seconds * rate); ++k)
  {
    const double t = k * dt;
    bias += walk * std::sqrt(dt) * normal(rng);
    const double measured = (t < stop ? acceleration(c, t) : 0.0) + bias + noise * std::sqrt(rate / 2.0) * normal(rng);
    const double w = check.update(measured, gain * velocity(c, t - lag), noise * noise * rate / 2.0, k > 0 ? dt : 0.0);
    r.min_weight = std::min(r.min_weight, w);
    r.weights.push_back(w);
  }
  return r;
}

TEST(WaveConsistency, AWaveThatIsMeasuredIsNeverScaled)
{
  // Broad seas and a narrow swell, at a buoy's 10 Hz up to 256 Hz, on a noisy sensor with a
  // wandering bias; the output half the wave or all of it: never scaled; all of it a quarter
  // second late: scaled by no more than a tenth.
  for (double rate : { 10.0, 100.0, 256.0 })
  {
    for (unsigned seed = 1; seed <= test::seedsToRun(3); ++seed)
    {
      std::mt19937_64 rng(seed);
      const std::vector<Component> wind = sea(60, 4.0, 12.0, 0.3, &rng);
      const std::vector<Component> swell = sea(8, 14.0, 17.0, 0.03, &rng);
      for (const auto* c : { &wind, &swell })
      {
        for (const auto& [gain, lag] : { std::pair(0.5, 0.0), std::pair(1.0, 0.0), std::pair(1.0, 0.25) })
        {
          const Trace r = feed(*c, rate, 900.0, INFINITY, 0.006, 6e-4, gain, seed, lag);
          // A lagging estimate's acceleration can exceed the measured near its zero crossings.
          EXPECT_GE(r.min_weight, lag > 0.0 ? 0.9 : 1.0) << rate << " Hz, seed " << seed << ", gain " << gain
                                                         << ", lag " << lag << (c == &swell ? ", swell" : ", wind sea");
        }
      }
    }
  }
}

TEST(WaveConsistency, AWaveThatHasStoppedFadesOut)
{
  // A hand-driven oscillation about 1.3 Hz and a slow sway, stopped at 30 s, on a noisy sensor
  // (0.01 m/s^2/sqrt(Hz)) whose bias wanders; the models go on describing it.
  for (double rate : { 10.0, 100.0, 256.0 })
  {
    std::mt19937_64 rng(7);
    std::vector<Component> motion = sea(5, 0.7, 0.9, 2.0, &rng);
    const std::vector<Component> sway = sea(2, 10.0, 12.0, 0.5, &rng);
    motion.insert(motion.end(), sway.begin(), sway.end());
    const Trace r = feed(motion, rate, 45.0, 30.0, 0.01, 6e-4, 1.0, 7);
    const auto at = [&](double t) { return r.weights[static_cast<std::size_t>(std::lround(t * rate))]; };
    const auto before = std::min_element(r.weights.begin(), r.weights.begin() + std::lround(30.0 * rate));
    EXPECT_EQ(*before, 1.0) << rate << " Hz, at " << (before - r.weights.begin()) / rate << " s";
    EXPECT_LT(at(35.0), 0.05) << rate << " Hz";
    // A fade, not a step: from 0.9 to 0.1 takes over half a second.
    const auto first_below = [&](double level) {
      std::size_t k = static_cast<std::size_t>(std::lround(30.0 * rate));
      while (k < r.weights.size() && r.weights[k] >= level)
        ++k;
      return k / rate;
    };
    EXPECT_GE(first_below(0.1) - first_below(0.9), 0.5) << rate << " Hz";
  }
}

TEST(WaveConsistency, NoOutputNoWeightAndBadInputIgnored)
{
  WaveConsistency check;
  for (int k = 0; k < 1000; ++k)
    EXPECT_EQ(check.update(0.1 * std::sin(k * 0.05), 0.0, 1e-4, 0.01), 1.0);
  EXPECT_EQ(check.update(NAN, 5.0, 1e-4, 0.01), 1.0);
  EXPECT_EQ(check.update(0.0, INFINITY, 1e-4, 0.01), 1.0);
  EXPECT_EQ(check.update(0.0, 5.0, 1e-4, 0.0), 1.0);
  EXPECT_EQ(check.update(0.0, 5.0, 1e-4, -0.01), 1.0);
  // A jump of the output after bad input is judged like any other.
  double w = 1.0;
  for (int k = 0; k < 300; ++k)
    w = check.update(0.0, 5.0 * std::sin(k * 0.2), 1e-4, 0.01);
  EXPECT_LT(w, 0.1);
  check.reset();
  EXPECT_EQ(check.weight(), 1.0);
}

}  // namespace
}  // namespace periodic_bias_compensation
