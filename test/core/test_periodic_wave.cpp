// PeriodicWave: a lock's model describes the wave after a period, at once when started from its
// history, and a changed or lost lock's model fades out without a step.
#include <gtest/gtest.h>

#include <cmath>

#include "periodic_bias_compensation/core/periodic_wave.h"

namespace periodic_bias_compensation
{
namespace
{
constexpr double kRate = 50.0, kFrequency = 0.125, kAmplitude = 0.8, kMemory = 3.0;
constexpr double kOmega = 2.0 * M_PI * kFrequency;
/// The fit's forgetting factor per sample, exp(-dt / kMemory).
const double kLambda = std::exp(-1.0 / (kRate * kMemory));

double acceleration(double t)
{
  return kAmplitude * std::sin(kOmega * t + 0.4);
}
double displacement(double t)
{
  return -acceleration(t) / (kOmega * kOmega);
}
double velocity(double t)
{
  return -kAmplitude * std::cos(kOmega * t + 0.4) / kOmega;
}

/// A model locked at kFrequency from the first sample on, fed `samples` samples of the wave;
/// *last: its last position [m].
PeriodicWave lockedWave(int samples, double* last)
{
  PeriodicWave wave;
  wave.setCapacity(1000);
  wave.reset(1);
  wave.start(kFrequency, kRate, kMemory, 1, true);
  for (int i = 0; i < samples; ++i)
    *last = wave.update(acceleration(i / kRate), kFrequency, i ? 1.0 / kRate : 0.0, kRate, kLambda).position;
  return wave;
}
}  // namespace

// Locked from the first sample: nothing is claimed before a period; after two, the displacement
// is the wave's to within 1 % of its amplitude.
TEST(PeriodicWave, DescribesTheWaveAfterAPeriod)
{
  PeriodicWave wave;
  wave.setCapacity(1000);
  wave.reset(1);
  wave.start(kFrequency, kRate, kMemory, 1, true);
  const double dt = 1.0 / kRate;
  double worst = 0.0;
  for (int i = 0; i < static_cast<int>(3.0 * kRate / kFrequency); ++i)
  {
    const double t = i * dt;
    const PeriodicWaveOutput out = wave.update(acceleration(t), kFrequency, i ? dt : 0.0, kRate, kLambda);
    EXPECT_EQ(out.ready, i + 1 >= kRate / kFrequency) << i;
    if (t > 2.0 / kFrequency)
      worst = std::max(worst, std::abs(out.position - displacement(t)));
  }
  EXPECT_LT(worst, 0.01 * kAmplitude / (kOmega * kOmega));
}

// A lock found after 30 s of unlocked samples starts from their history: ready and right on the
// first locked sample.
TEST(PeriodicWave, StartsFromItsHistory)
{
  PeriodicWave wave;
  wave.setCapacity(1000);
  wave.reset(1);
  const double dt = 1.0 / kRate;
  int i = 0;
  for (; i < static_cast<int>(30.0 * kRate); ++i)
    wave.push(acceleration(i * dt));
  wave.start(kFrequency, kRate, kMemory, 1, true);
  const PeriodicWaveOutput out = wave.update(acceleration(i * dt), kFrequency, dt, kRate, kLambda);
  ASSERT_TRUE(out.ready);
  EXPECT_NEAR(out.position, displacement(i * dt), 0.01 * kAmplitude / (kOmega * kOmega));
  EXPECT_NEAR(out.residual, 0.0, 0.01 * kAmplitude);
}

// The velocity a new model takes over from the slow channel: the wave's at the previous sample when
// the slow channel started long ago, less the wave's at that start when it was within a period;
// nothing while an older model fades into the new one.
TEST(PeriodicWave, StartVelocityIsWhatTheSlowChannelIntegrated)
{
  const double dt = 1.0 / kRate;
  const int n = static_cast<int>(30.0 * kRate);
  const double tolerance = 0.01 * kAmplitude / kOmega;
  const double last = (n - 1) * dt;  // the previous sample's time at start()
  for (const double span : { double(INFINITY), 100.0, 3.0 })
  {
    PeriodicWave wave;
    wave.setCapacity(1000);
    wave.reset(1);
    for (int i = 0; i < n; ++i)
      wave.push(acceleration(i * dt));
    wave.start(kFrequency, kRate, kMemory, 1, true, span);
    const double expected = span < 1.0 / kFrequency ? velocity(last) - velocity(last - span) : velocity(last);
    EXPECT_NEAR(wave.startVelocity(), expected, tolerance) << span;
  }
  double unused = 0.0;
  PeriodicWave moved = lockedWave(n, &unused);
  moved.start(2.0 * kFrequency, kRate, kMemory, 1, true);
  EXPECT_EQ(moved.startVelocity(), 0.0);
}

// A lost lock: its model, extrapolated, fades with kFadeTime into the estimate it is blended with
// (here zero), without a step; gone once its weight is below kFadeEnd. A model that never saw a
// period leaves nothing to fade.
TEST(PeriodicWave, ALostLockFadesOut)
{
  const double dt = 1.0 / kRate;
  int i = static_cast<int>(20.0 * kRate);
  double last = 0.0;
  PeriodicWave wave = lockedWave(i, &last);
  wave.retire();
  double a = 0.0, x = 0.0, v = 0.0;
  wave.fade(dt, &a, &x, &v);
  EXPECT_NEAR(x, last, 0.02 * kAmplitude / (kOmega * kOmega));  // no step
  const double t_lost = i * dt;
  for (++i; i < static_cast<int>(40.0 * kRate); ++i)
  {
    a = x = v = 0.0;
    wave.fade(dt, &a, &x, &v);
    const double t = i * dt;
    const double weight = std::exp(-(t - t_lost) / PeriodicWave::kFadeTime);
    if (weight >= PeriodicWave::kFadeEnd * 1.1)
    {
      EXPECT_NEAR(x, weight * displacement(t), 0.02 * kAmplitude / (kOmega * kOmega)) << t;
    }
    else if (weight < PeriodicWave::kFadeEnd * 0.9)
    {
      EXPECT_EQ(x, 0.0) << t;
    }
  }

  PeriodicWave fresh;
  fresh.setCapacity(1000);
  fresh.reset(1);
  fresh.start(kFrequency, kRate, kMemory, 1, true);
  fresh.update(acceleration(0.0), kFrequency, 0.0, kRate, kLambda);
  fresh.retire();
  a = x = v = 1.0;
  fresh.fade(dt, &a, &x, &v);
  EXPECT_EQ(x, 1.0);
}

// A lock that moves (0.125 -> 0.5 Hz): the old model fades at its own frequency, so the wave
// estimate it is blended into goes on from where it was, without a step.
TEST(PeriodicWave, AMovedLockFadesAtItsOwnFrequency)
{
  const double dt = 1.0 / kRate;
  int i = static_cast<int>(20.0 * kRate);
  double last = 0.0;
  PeriodicWave wave = lockedWave(i, &last);
  wave.start(4.0 * kFrequency, kRate, kMemory, 1, true);
  double a = 0.0, x = 0.0, v = 0.0;
  wave.fade(dt, &a, &x, &v);
  EXPECT_NEAR(x, displacement(i * dt), 0.02 * kAmplitude / (kOmega * kOmega));
  EXPECT_NEAR(x, last, 0.05 * kAmplitude / (kOmega * kOmega));
}
}  // namespace periodic_bias_compensation
