// BroadbandWave: when the broadband estimate takes over from the harmonic model, and when it
// must not (no sea, a horizontal axis before its spectrum or while blocked).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "periodic_bias_compensation/core/broadband_wave.h"
#include "periodic_bias_compensation/core/heave_filter.h"

namespace periodic_bias_compensation
{
namespace
{
/// A broad sea of 60 components over 0.07-0.3 Hz with random phases: displacement and
/// acceleration at t.
struct BroadSea
{
  explicit BroadSea(double rms, unsigned seed)
  {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int k = 0; k < 60; ++k)
    {
      frequency.push_back(0.07 + 0.23 * (k + u(rng)) / 60.0);
      phase.push_back(2.0 * M_PI * u(rng));
    }
    amplitude = rms * std::sqrt(2.0 / 60.0);
  }
  void at(double t, double* x, double* a) const
  {
    *x = *a = 0.0;
    for (size_t k = 0; k < frequency.size(); ++k)
    {
      const double w = 2.0 * M_PI * frequency[k], s = amplitude * std::sin(w * t + phase[k]);
      *x += s;
      *a -= w * w * s;
    }
  }
  std::vector<double> frequency, phase;
  double amplitude;
};

constexpr double kRate = 20.0;

/// Sample i of an acceleration a [m/s^2] as measured (white noise of 0.004 m/s^2/sqrt(Hz), no
/// calibrated offset), with a lock whose model explains none of it; the caller sets what the
/// harmonic model does otherwise.
BroadbandWaveInput measured(long i, double a, std::mt19937_64* rng)
{
  BroadbandWaveInput in;
  in.raw = a + std::normal_distribution<double>(0.0, 0.004 * std::sqrt(kRate / 2.0))(*rng);
  in.offset_free = in.raw;
  in.residual = in.raw;
  in.locked = true;
  in.dt = i > 0 ? 1.0 / kRate : 0.0;
  in.rate = kRate;
  return in;
}

/// Feeds `seconds` of the sea (or none) with white noise 0.004 m/s^2/sqrt(Hz); the harmonic model,
/// when `locked`, explains nothing of a broad sea (its residual is the whole acceleration).
/// Returns the last output; the largest weight and largest blended displacement (weight times
/// the broadband displacement) go to `largest_weight` and `largest_blended`.
BroadbandWaveOutput feed(BroadbandWave* wave, const BroadSea* sea, double seconds, bool allowed, double* t,
                         std::mt19937_64* rng, double* largest_weight = nullptr, bool locked = true,
                         double* largest_blended = nullptr)
{
  BroadbandWaveOutput out;
  const double end = *t + seconds;
  for (; *t < end; *t += 1.0 / kRate)
  {
    double x = 0.0, a = 0.0;
    if (sea)
      sea->at(*t, &x, &a);
    BroadbandWaveInput in = measured(*t > 0.0 ? 1 : 0, a, rng);
    in.raw += 0.02;  // a calibrated offset
    in.residual = in.raw;
    in.locked = locked;
    in.allowed = allowed;
    out = wave->update(in);
    if (largest_weight)
      *largest_weight = std::max(*largest_weight, out.weight);
    if (largest_blended)
      *largest_blended = std::max(*largest_blended, std::abs(out.weight * out.estimate.position));
  }
  return out;
}
}  // namespace

// No sea: without a lock nothing is measured as missed and no share is taken; with a spurious
// lock on the noise a share may be, but what it adds stays under a centimetre.
TEST(BroadbandWave, NoSeaNoMotion)
{
  std::mt19937_64 rng(1);
  BroadbandWave unlocked(true);
  double t = 0.0, largest = 0.0;
  feed(&unlocked, nullptr, 600.0, true, &t, &rng, &largest, false);
  EXPECT_EQ(largest, 0.0);
  BroadbandWave locked(true);
  double blended = 0.0;
  t = 0.0;
  feed(&locked, nullptr, 600.0, true, &t, &rng, nullptr, true, &blended);
  EXPECT_LT(blended, 0.01);
}

// A broad sea the harmonic model misses: the vertical axis takes the broadband estimate, which
// then follows the displacement.
TEST(BroadbandWave, BroadSeaTakesOverVertically)
{
  const BroadSea sea(0.5, 2);
  BroadbandWave wave(true);
  std::mt19937_64 rng(2);
  double t = 0.0;
  const BroadbandWaveOutput out = feed(&wave, &sea, 400.0, true, &t, &rng);
  EXPECT_GT(out.weight, 0.8);
  double error2 = 0.0, truth2 = 0.0;
  for (int k = 0; k < 60 * static_cast<int>(kRate); ++k)
  {
    const BroadbandWaveOutput o = feed(&wave, &sea, 1.0 / kRate, true, &t, &rng);
    double x, a;
    sea.at(t - 1.0 / kRate, &x, &a);
    error2 += std::pow(o.estimate.position - x, 2);
    truth2 += x * x;
  }
  EXPECT_LT(std::sqrt(error2 / truth2), 0.15);
  EXPECT_GT(out.position_variance, 0.0);
}

// Before any lock the harmonic model gives nothing: once the spectral estimate holds the sea, the
// vertical axis takes it whole, and it follows the displacement.
TEST(BroadbandWave, WithoutALockTheSpectralEstimateTakesTheSea)
{
  const BroadSea sea(0.5, 4);
  BroadbandWave wave(true);
  std::mt19937_64 rng(4);
  double t = 0.0, largest = 0.0;
  feed(&wave, &sea, WienerHeave::kFirstDesign - 5.0, true, &t, &rng, &largest, false);
  EXPECT_EQ(largest, 0.0) << "before the first design";
  EXPECT_GT(feed(&wave, &sea, 30.0, true, &t, &rng, nullptr, false).weight, 0.95);
  double error2 = 0.0, truth2 = 0.0;
  for (int k = 0; k < 60 * static_cast<int>(kRate); ++k)
  {
    const BroadbandWaveOutput o = feed(&wave, &sea, 1.0 / kRate, true, &t, &rng, nullptr, false);
    double x, a;
    sea.at(t - 1.0 / kRate, &x, &a);
    error2 += std::pow(o.weight * o.estimate.position - x, 2);
    truth2 += x * x;
  }
  EXPECT_LT(std::sqrt(error2 / truth2), 0.3);
}

// Without a lock nothing is published until the first design; from then on the design is the
// output within a second, not faded in over seconds from nothing and from the fixed filter's
// start (which rings for minutes after a start in the waves). Over its first ten seconds the
// published displacement is pooled over seeds.
TEST(BroadbandWave, TheFirstDesignIsPublishedAtOnceWithoutALock)
{
  double error2 = 0.0, truth2 = 0.0;
  for (unsigned seed = 5; seed < 13; ++seed)
  {
    const BroadSea sea(0.5, seed);
    BroadbandWave wave(true);
    std::mt19937_64 rng(seed);
    double t = 0.0;
    feed(&wave, &sea, WienerHeave::kFirstDesign + WienerHeave::kDesignDelay, true, &t, &rng, nullptr, false);
    for (int k = 0; k < 10 * static_cast<int>(kRate); ++k)
    {
      const BroadbandWaveOutput o = feed(&wave, &sea, 1.0 / kRate, true, &t, &rng, nullptr, false);
      if (k == static_cast<int>(kRate))
      {
        EXPECT_GT(o.weight, 0.9) << "one second after the design, seed " << seed;
      }
      double x, a;
      sea.at(t - 1.0 / kRate, &x, &a);
      error2 += std::pow(o.weight * o.estimate.position - x, 2);
      truth2 += x * x;
    }
  }
  EXPECT_LT(std::sqrt(error2 / truth2), 0.42);
}

// Horizontally: no share before the spectral estimate exists (the fixed filter never stands in),
// a share once it does, and out within a second of being blocked (a turn).
TEST(BroadbandWave, HorizontalOnlySpectralAndBlockable)
{
  const BroadSea sea(0.5, 3);
  BroadbandWave wave(false);
  std::mt19937_64 rng(3);
  double t = 0.0, largest = 0.0;
  feed(&wave, &sea, WienerHeave::kFirstDesign - 5.0, true, &t, &rng, &largest);
  EXPECT_EQ(largest, 0.0) << "before the first design";
  EXPECT_GT(feed(&wave, &sea, 300.0, true, &t, &rng).weight, 0.8);
  EXPECT_LT(feed(&wave, &sea, 1.0, false, &t, &rng).weight, 0.05) << "one second after a turn began";
  largest = 0.0;
  feed(&wave, &sea, 60.0, false, &t, &rng, &largest);
  EXPECT_LT(largest, 0.05);
}

// Horizontally, for the first kResidualSettling of a run, a design without a lock is no sea (a
// short record of a hand's or a rig's motion reads as one): no share before, the whole share
// after, on the same broad sea.
TEST(BroadbandWave, NoLockNoHorizontalShareInTheFirstMinute)
{
  const BroadSea sea(0.5, 5);
  BroadbandWave wave(false);
  std::mt19937_64 rng(5);
  double t = 0.0, largest = 0.0;
  feed(&wave, &sea, BroadbandWave::kResidualSettling - 1.0, true, &t, &rng, &largest, false);
  EXPECT_EQ(largest, 0.0);
  EXPECT_GT(feed(&wave, &sea, 30.0, true, &t, &rng, nullptr, false).weight, 0.9);
}

// A hold that ends (the sea's yaw, a turn's hold run out): the share returns as fast as it left,
// within a second and a half, not at the pace that smooths its target (kWeightTime, 2 s).
TEST(BroadbandWave, HeldShareReturnsAsFastAsItLeft)
{
  const BroadSea sea(0.5, 3);
  BroadbandWave wave(false);
  std::mt19937_64 rng(3);
  double t = 0.0;
  const double before = feed(&wave, &sea, WienerHeave::kFirstDesign + 300.0, true, &t, &rng).weight;
  ASSERT_GT(before, 0.8);
  EXPECT_LT(feed(&wave, &sea, 2.0, false, &t, &rng).weight, 0.05);
  EXPECT_GT(feed(&wave, &sea, 1.5, true, &t, &rng).weight, before - 0.1) << "1.5 s after the hold";
}

// A turn changes every encounter frequency: the vertical axis crosses over to the fixed filter
// without a step while the spectrum is measured anew, and back once the new record gives a design.
TEST(BroadbandWave, TurnHandsTheVerticalToTheFixedFilterAndBack)
{
  const BroadSea sea(0.5, 4);
  BroadbandWave wave(true);
  HeaveFilter fixed;  // the same corner as BroadbandWave's own
  std::mt19937_64 rng(4);
  const double dt = 1.0 / kRate, turn_start = 400.0, turn_end = 430.0;
  double previous = 0.0, largest_step_before = 0.0, largest_step_turn = 0.0;
  double fixed_gap_turn = 0.0, fixed_gap_after = 0.0, error2 = 0.0, fixed_error2 = 0.0, truth2 = 0.0;
  for (long i = 0; i < static_cast<long>(800 * kRate); ++i)
  {
    const double t = i * dt;
    double x, a;
    sea.at(t, &x, &a);
    BroadbandWaveInput in = measured(i, a, &rng);
    in.turning = t >= turn_start && t < turn_end;
    const double position = wave.update(in).estimate.position;
    const double fixed_position = fixed.update(in.offset_free, in.dt).position;
    const double step = std::abs(position - previous);
    previous = position;
    if (t > 300.0 && t < turn_start)
      largest_step_before = std::max(largest_step_before, step);
    if (t >= turn_start && t < turn_start + 10.0)
      largest_step_turn = std::max(largest_step_turn, step);
    if (t > turn_start + 15.0 && t < turn_end)
      fixed_gap_turn = std::max(fixed_gap_turn, std::abs(position - fixed_position));
    if (t > turn_end + WienerHeave::kRestartDesign + 15.0)
      fixed_gap_after = std::max(fixed_gap_after, std::abs(position - fixed_position));
    if (t > turn_end + 180.0)  // the first designs of a new record are coarse
    {
      fixed_error2 += (fixed_position - x) * (fixed_position - x);
      error2 += (position - x) * (position - x);
      truth2 += x * x;
    }
  }
  EXPECT_LT(largest_step_turn, 1.5 * largest_step_before) << "no step at the hand-over";
  EXPECT_LT(fixed_gap_turn, 0.01) << "the fixed filter's output while the ship turns";
  EXPECT_GT(fixed_gap_after, 0.05) << "the spectral estimate is back";
  EXPECT_LT(std::sqrt(error2 / truth2), 0.15);
  EXPECT_LT(error2, 0.5 * fixed_error2);
  std::printf("error from 180 s after the turn: spectral %.3f, fixed filter %.3f of the RMS\n",
              std::sqrt(error2 / truth2), std::sqrt(fixed_error2 / truth2));
}

// A model locked well above the displacement's peak whose residual shows no miss yet (its first
// minute): the spectral design alone, once it holds the sea, gives it the whole share.
TEST(BroadbandWave, ALockOffThePeakGivesWayOnceTheDesignHoldsTheSea)
{
  const BroadSea sea(0.5, 6);
  BroadbandWave wave(true);
  std::mt19937_64 rng(6);
  double smallest_weight = 1.0;
  for (long i = 0; i < static_cast<long>((WienerHeave::kFirstDesign + 40.0) * kRate); ++i)
  {
    const double t = i / kRate;
    double x = 0.0, a = 0.0;
    sea.at(t, &x, &a);
    BroadbandWaveInput in = measured(i, a, &rng);
    in.residual = 0.0;
    in.frequency = 0.6;
    const BroadbandWaveOutput out = wave.update(in);
    if (t > WienerHeave::kFirstDesign + 20.0)
      smallest_weight = std::min(smallest_weight, out.weight);
  }
  EXPECT_GT(smallest_weight, 0.95);
}

// A long swell that the harmonic model, locked to a shorter period, fits in acceleration but
// turns into far too little displacement (it divides by its own frequency squared): the
// acceleration residual is small, the displacement error large. The lock lies far from the
// displacement spectrum's peak, so the broadband estimate takes the whole wave output.
TEST(BroadbandWave, ModelLockedElsewhereGivesWayToTheBroadbandEstimate)
{
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> frequency, phase;
  for (int k = 0; k < 20; ++k)
  {
    frequency.push_back(0.055 + 0.02 * (k + u(rng)) / 20.0);
    phase.push_back(2.0 * M_PI * u(rng));
  }
  const double amplitude = 0.5 * std::sqrt(2.0 / 20.0), locked = 2.0 * M_PI * 0.18;
  BroadbandWave wave(true);
  double blended2 = 0.0, broadband2 = 0.0, harmonic2 = 0.0, smallest_weight = 1.0;
  const double dt = 1.0 / kRate;
  for (long i = 0; i < static_cast<long>(900 * kRate); ++i)
  {
    const double t = i * dt;
    double x = 0.0, a = 0.0;
    for (size_t k = 0; k < frequency.size(); ++k)
    {
      const double w = 2.0 * M_PI * frequency[k], s = amplitude * std::sin(w * t + phase[k]);
      x += s;
      a -= w * w * s;
    }
    BroadbandWaveInput in = measured(i, a, &rng);
    in.residual = 0.2 * a;
    in.harmonic_position = -0.8 * a / (locked * locked);
    in.frequency = locked / (2.0 * M_PI);
    const BroadbandWaveOutput out = wave.update(in);
    if (t < 300.0)
      continue;
    const double blended = in.harmonic_position + out.weight * (out.estimate.position - in.harmonic_position);
    blended2 += (blended - x) * (blended - x);
    broadband2 += (out.estimate.position - x) * (out.estimate.position - x);
    harmonic2 += (in.harmonic_position - x) * (in.harmonic_position - x);
    smallest_weight = std::min(smallest_weight, out.weight);
  }
  std::printf(
      "model locked elsewhere: smallest share %.2f, RMS error blended %.3f, broadband %.3f, "
      "harmonic %.3f m\n",
      smallest_weight, std::sqrt(blended2 / (600 * kRate)), std::sqrt(broadband2 / (600 * kRate)),
      std::sqrt(harmonic2 / (600 * kRate)));
  EXPECT_GT(smallest_weight, 0.95);
  EXPECT_LT(blended2, 1.2 * broadband2);
}

// A narrow sea that the harmonic model follows at its peak (a sinusoid of 0.1 Hz, 0.3 m, with
// noise; the model's displacement within 2 % of it): the share is the inverse-variance one, never
// overruled to the whole output (which it reaches within seconds when the lock is off the peak).
TEST(BroadbandWave, ALockOnTheDisplacementPeakIsNotOverruled)
{
  std::mt19937_64 rng(6);
  const double w = 2.0 * M_PI * 0.1, dt = 1.0 / kRate;
  BroadbandWave wave(false);
  double largest_weight = 0.0;
  for (long i = 0; i < static_cast<long>(900 * kRate); ++i)
  {
    const double t = i * dt, x = 0.3 * std::sin(w * t), a = -w * w * x;
    BroadbandWaveInput in = measured(i, a, &rng);
    in.residual = in.raw - 0.98 * a;
    in.harmonic_position = 0.98 * x;
    in.frequency = 0.1;
    const BroadbandWaveOutput out = wave.update(in);
    if (t >= 300.0)
      largest_weight = std::max(largest_weight, out.weight);
  }
  std::printf("lock on the displacement peak: largest share %.2f\n", largest_weight);
  EXPECT_LT(largest_weight, 0.9);
}

// A bench shaken at one frequency (1 cm at 0.443 Hz) that the harmonic model describes; its
// residual holds the noise and, for its first seconds, what a fit that is still converging
// leaves (the oscillation decaying with a 3 s memory). Over the 60 s of such a bench the share
// stays closed: neither the start nor the scatter of the noise's mean square is a miss.
TEST(BroadbandWave, AConvergingFitIsNoMiss)
{
  const double rate = 87.7, w = 2.0 * M_PI * 0.443, amplitude = 0.01;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.003 * std::sqrt(rate / 2.0));
  BroadbandWave wave(true);
  double largest = 0.0;
  for (long i = 0; i < static_cast<long>(60.0 * rate); ++i)
  {
    const double t = i / rate, x = amplitude * std::sin(w * t), a = -w * w * x;
    const double converging = std::exp(-t / 3.0) * a;
    BroadbandWaveInput in;
    in.raw = a + noise(rng);
    in.offset_free = in.raw;
    in.residual = in.raw - a + converging;
    in.harmonic_position = (1.0 - std::exp(-t / 3.0)) * x;
    in.locked = true;
    in.frequency = 0.443;
    in.dt = i > 0 ? 1.0 / rate : 0.0;
    in.rate = rate;
    in.rate_settled = t > 1.0;
    const BroadbandWaveOutput out = wave.update(in);
    if (t > 20.0)
      largest = std::max(largest, out.weight);
  }
  EXPECT_LT(largest, BroadbandWave::kMinWeight);
}

}  // namespace periodic_bias_compensation
