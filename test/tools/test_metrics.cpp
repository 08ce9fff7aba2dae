// The metrics of evaluate_compensator's tables on synthetic runs whose errors are known: a scorer
// given a known offset, nearest-rank percentiles and medians of small vectors, the high-pass
// filter's step and sinusoid responses, the period scorer on a sinusoid of known period, the
// two baselines on a constant acceleration, and the causal bound on sinusoids with and without
// noise.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "periodic_bias_compensation/tools/metrics.h"

namespace pbc = periodic_bias_compensation;
namespace metrics = periodic_bias_compensation::metrics;
namespace sim = periodic_bias_compensation::sim;
using pbc::Quaternion;
using pbc::Vector3;

namespace
{
constexpr double kGravity = sim::kStandardGravity;

/// A run of `duration` s at `rate` Hz from t = 1000 s (stamps exact), each sample's truth set by
/// `fill` from its elapsed time.
std::vector<sim::Sample> run(double rate, double duration, const std::function<void(double, sim::Sample*)>& fill)
{
  std::vector<sim::Sample> samples;
  for (int k = 0; k <= static_cast<int>(std::lround(duration * rate)); ++k)
  {
    sim::Sample s;
    s.index = k;
    s.elapsed = k / rate;
    s.t = 1000.0 + s.elapsed;
    s.stamp = s.t;
    s.accel = Vector3(0, 0, kGravity);
    fill(s.elapsed, &s);
    samples.push_back(s);
  }
  return samples;
}

/// Amplitude and phase of the component at `frequency` [Hz] of y[first..] (sample k taken at t =
/// k / rate, a whole number of periods): y = gain sin(2 pi frequency t + phase) + other frequencies.
void component(const std::vector<double>& y, int first, double frequency, double rate, double* gain, double* phase)
{
  double s = 0.0, c = 0.0;
  for (int k = first; k < static_cast<int>(y.size()); ++k)
  {
    s += y[k] * std::sin(2 * M_PI * frequency * k / rate);
    c += y[k] * std::cos(2 * M_PI * frequency * k / rate);
  }
  s *= 2.0 / (y.size() - first);
  c *= 2.0 / (y.size() - first);
  *gain = std::hypot(s, c);
  *phase = std::atan2(c, s);
}

/// The high-pass filter's output on x = sin(2 pi frequency t), t = k / rate, for `seconds`.
std::vector<double> highPassSine(double cutoff, double frequency, double rate, double seconds)
{
  metrics::HighPass filter(cutoff, rate);
  std::vector<double> out;
  for (int k = 0; k < static_cast<int>(std::lround(seconds * rate)); ++k)
    out.push_back(filter(Vector3(std::sin(2 * M_PI * frequency * k / rate), 0, 0)).x());
  return out;
}
}  // namespace

TEST(Metrics, ScorerGivesTheRmsOfAKnownOffset)
{
  // A ship under way (slow motion from a start far from zero) with a wave of 8 s period; the
  // estimate is off by d in the slow motion and by e in the wave motion from settle on, by 50 m
  // before it. 20.25 s to 100 s at 4 Hz: 320 samples, ten wave periods.
  const Vector3 p0(100.0, -200.0, 3.0), amplitude(1.0, 2.0, 0.0);
  const Vector3 d(0.3, -0.4, 0.05), e(0.1, -0.2, 0.02);
  const double settle = 20.25;
  const auto samples = run(4.0, 100.0, [&](double t, sim::Sample* s) {
    s->truth.slow_position = p0 + Vector3(1.5 * t, -0.5 * t, 0.0);
    s->truth.wave_position = amplitude * std::sin(2 * M_PI * 0.125 * t);
    s->truth.position = s->truth.slow_position + s->truth.wave_position;
  });
  metrics::Scorer scorer(samples.front(), settle);
  Vector3 slow, wave;
  for (const auto& s : samples)
  {
    const Vector3 before_settling = Vector3::Constant(s.elapsed < settle ? 50.0 : 0.0);
    slow = s.truth.slow_position - p0 + d + before_settling;
    wave = s.truth.wave_position + e;
    scorer.add(s, slow, wave);
  }
  const metrics::Errors errors = scorer.finish(samples.back(), slow, wave);
  for (int i = 0; i < 3; ++i)
  {
    SCOPED_TRACE("axis " + std::to_string(i));
    EXPECT_NEAR(errors.slow_rms[i], std::abs(d[i]), 1e-9);
    EXPECT_NEAR(errors.total_rms[i], std::abs(d[i] + e[i]), 1e-9);
    EXPECT_NEAR(errors.slow_final[i], std::abs(d[i]), 1e-9);
    EXPECT_NEAR(errors.total_final[i], std::abs(d[i] + e[i]), 1e-9);
    EXPECT_NEAR(errors.slow_at[0][i], std::abs(d[i]), 1e-9);  // at 60 s
    EXPECT_TRUE(std::isnan(errors.slow_at[1][i]));            // the run is shorter than 10 min
    EXPECT_TRUE(std::isnan(errors.slow_at[2][i]));
  }
  // RMS of the true wave A / sqrt(2), its standard deviation the same: Hs = 4 A / sqrt(2).
  for (int i = 0; i < 2; ++i)
  {
    EXPECT_NEAR(errors.wave_rms_percent[i], 100.0 * std::abs(e[i]) / (amplitude[i] / std::sqrt(2.0)), 1e-9);
    EXPECT_NEAR(errors.wave_hs_percent[i], 100.0 * std::abs(e[i]) / (4.0 * amplitude[i] / std::sqrt(2.0)), 1e-9);
  }
  // No true wave on z: no share of it.
  EXPECT_TRUE(std::isnan(errors.wave_rms_percent.z()));
  EXPECT_TRUE(std::isnan(errors.wave_hs_percent.z()));
}

TEST(Metrics, CheckpointTakesASampleATenthOfASecondBeforeIt)
{
  // Ends one sample (1/16 s) short of 60 s; the slow-motion error grows 1 cm/s.
  const auto samples = run(16.0, 60.0 - 1.0 / 16.0, [](double, sim::Sample*) {});
  metrics::Scorer scorer(samples.front(), std::numeric_limits<double>::infinity());
  Vector3 slow;
  for (const auto& s : samples)
  {
    slow = Vector3::Constant(0.01 * s.elapsed);
    scorer.add(s, slow, Vector3::Zero());
  }
  const metrics::Errors errors = scorer.finish(samples.back(), slow, Vector3::Zero());
  EXPECT_DOUBLE_EQ(errors.slow_at[0].x(), 0.01 * 59.9375);
  EXPECT_TRUE(std::isnan(errors.slow_at[1].x()));
  // Settling never ends: no RMS error.
  EXPECT_TRUE(std::isnan(errors.slow_rms.x()));
  EXPECT_TRUE(std::isnan(errors.total_rms.x()));
}

TEST(Metrics, PercentileIsTheNearestRank)
{
  EXPECT_EQ(metrics::percentile({ 5, 1, 4, 2, 3 }, 0.5), 3);
  EXPECT_EQ(metrics::percentile({ 5, 1, 4, 2, 3 }, 0.0), 1);
  EXPECT_EQ(metrics::percentile({ 5, 1, 4, 2, 3 }, 0.95), 5);  // rank floor(4.75) = 4
  EXPECT_EQ(metrics::percentile({ 5, 1, 4, 2, 3 }, 0.7), 4);   // rank floor(3.5) = 3
  // Even count: the upper of the two middle values, never their mean.
  EXPECT_EQ(metrics::percentile({ 4, 1, 3, 2 }, 0.5), 3);
  EXPECT_EQ(metrics::percentile({ 4, 1, 3, 2 }, 1.0), 4);  // at most the largest
  std::vector<double> twenty;
  for (int v = 20; v >= 1; --v)
    twenty.push_back(v);
  EXPECT_EQ(metrics::percentile(twenty, 0.95), 20);
  EXPECT_EQ(metrics::percentile(twenty, 0.9), 19);
  EXPECT_EQ(metrics::percentile(twenty, 0.25), 6);
  EXPECT_TRUE(std::isnan(metrics::percentile({}, 0.5)));
}

TEST(Metrics, MedianOfTheFiniteValues)
{
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(metrics::median({ 3, 1, 2 }), 2);
  EXPECT_EQ(metrics::median({ 4, 1, 3, 2 }), 2.5);  // even count: mean of the two middle ones
  EXPECT_EQ(metrics::median({ 7, -1 }), 3);
  EXPECT_EQ(metrics::median({ 5 }), 5);
  EXPECT_EQ(metrics::median({ 2, 2, 9, 2 }), 2);
  EXPECT_EQ(metrics::median({ nan, 1, inf, 3, -inf }), 2);  // the non-finite values are left out
  EXPECT_EQ(metrics::median({ nan, 10, 1, nan, 4 }), 4);
  EXPECT_TRUE(std::isnan(metrics::median({ nan, inf })));
  EXPECT_TRUE(std::isnan(metrics::median({})));
}

TEST(Metrics, HighPassRemovesAConstant)
{
  // A step (its state starts at zero) decays as a first-order high-pass's, exp(-2 pi f_c t).
  const double cutoff = 0.1, rate = 100.0;
  metrics::HighPass filter(cutoff, rate);
  const Vector3 x(1.0, -2.0, 0.5);
  const Vector3 first = filter(x);
  EXPECT_GT(first.x(), 0.99);
  Vector3 y;
  for (int k = 1; k <= 1000; ++k)
    y = filter(x);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(y[i] / first[i], std::exp(-2 * M_PI * cutoff * 10.0), 1e-3 * std::exp(-2 * M_PI * cutoff * 10.0));
  for (int k = 1001; k <= 6000; ++k)
    y = filter(x);
  EXPECT_LT(y.norm(), 1e-12);
}

TEST(Metrics, HighPassPassesASinusoidWithTheFirstOrderGain)
{
  // 60 s, the last 10 s measured (the start's transient has decayed by exp(-2 pi 0.1 50)).
  const double cutoff = 0.1, rate = 100.0;
  double gain = 0.0, phase = 0.0;
  // Ten times the corner: |H| = 1 / sqrt(1 + (f_c / f)^2), phase lead atan(f_c / f).
  component(highPassSine(cutoff, 1.0, rate, 60.0), 5000, 1.0, rate, &gain, &phase);
  EXPECT_NEAR(gain, 1.0 / std::sqrt(1.01), 1e-4);
  EXPECT_NEAR(phase, std::atan(0.1), 1e-3);
  // At the corner (prewarped): 1 / sqrt(2), 45 degrees ahead.
  component(highPassSine(cutoff, cutoff, rate, 60.0), 5000, cutoff, rate, &gain, &phase);
  EXPECT_NEAR(gain, 1.0 / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(phase, M_PI / 4, 1e-6);
}

TEST(Metrics, IntegrateRawOfAConstantAccelerationIsHalfATSquared)
{
  // Level acceleration a, IMU turned 90 degrees in yaw and tilted 10 degrees in roll (its reported
  // orientation exact); the truth is the path a t^2 / 2 from p0.
  const Vector3 a(0.1, -0.05, 0.02), p0(10.0, 20.0, -1.0);
  const Quaternion q = Quaternion(Eigen::AngleAxisd(M_PI / 2, Vector3::UnitZ())) *
                       Quaternion(Eigen::AngleAxisd(10.0 * M_PI / 180.0, Vector3::UnitX()));
  const double rate = 8.0, duration = 100.0;
  const auto samples = run(rate, duration, [&](double t, sim::Sample* s) {
    s->orientation = q;
    s->accel = q.conjugate() * (a + Vector3(0, 0, kGravity));
    s->truth.slow_position = p0 + 0.5 * a * t * t;
    s->truth.position = s->truth.slow_position;
  });
  const metrics::Errors errors = metrics::integrateRaw(samples, kGravity);
  // The trapezoidal rule is exact for a constant acceleration: on the path at every checkpoint.
  for (int i = 0; i < 3; ++i)
  {
    SCOPED_TRACE("axis " + std::to_string(i));
    EXPECT_NEAR(errors.slow_final[i], 0.0, 1e-6);
    EXPECT_NEAR(errors.total_final[i], 0.0, 1e-6);
    EXPECT_NEAR(errors.slow_at[0][i], 0.0, 1e-6);
    // Scored at the checkpoints and the end only.
    EXPECT_TRUE(std::isnan(errors.slow_rms[i]));
    EXPECT_TRUE(std::isnan(errors.wave_rms_percent[i]));
  }
}

TEST(Metrics, HighPassBaselineForgetsAConstantAccelerationBias)
{
  // An IMU at rest with an accelerometer bias: double integration drifts by b t^2 / 2 (2250 m on x
  // after 300 s); the three high-passes take the bias out completely.
  const Vector3 bias(0.05, -0.03, 0.02);
  const auto samples = run(10.0, 300.0, [&](double, sim::Sample* s) { s->accel = bias + Vector3(0, 0, kGravity); });
  const metrics::Errors raw = metrics::integrateRaw(samples, kGravity);
  EXPECT_NEAR(raw.total_final.x(), 0.5 * 0.05 * 300.0 * 300.0, 1e-6);  // b t^2 / 2
  const metrics::Errors baseline = metrics::highPassBaseline(samples, kGravity, 20.0);
  for (int i = 0; i < 3; ++i)
  {
    SCOPED_TRACE("axis " + std::to_string(i));
    EXPECT_LT(baseline.total_final[i], 1e-9);
    EXPECT_EQ(baseline.slow_final[i], 0.0);  // its slow motion is zero, as the truth's here
    EXPECT_LT(baseline.total_rms[i], 1e-5);  // the start's transient, after 20 s (4 mm RMS from 0 s)
  }
}

TEST(Metrics, PeriodScorerOnASinusoidOfKnownPeriod)
{
  // True wave acceleration at 0.1 Hz on every axis, 400 s at 10 Hz, one FFT hop a second. x locks
  // at 100 s on the true frequency; y at 50 s, 10 % high, and loses the lock from 200 s to 300 s
  // (its frequency meanwhile nonsense); z never locks.
  const double rate = 10.0, f0 = 0.1;
  const auto samples = run(rate, 400.0 - 1.0 / rate, [&](double t, sim::Sample* s) {
    s->truth.wave_acceleration = Vector3(0.5, 1.0, 0.2) * std::sin(2 * M_PI * f0 * t);
  });
  pbc::CompensatorConfig config;
  ASSERT_EQ(config.fft_hop, 1.0);
  metrics::PeriodScorer scorer(config, rate);
  for (const auto& s : samples)
  {
    pbc::CompensatorOutput out;
    out.axes[0].locked = s.elapsed >= 100.0;
    out.axes[0].frequency = out.axes[0].locked ? f0 : 0.0;
    out.axes[1].locked = s.elapsed >= 50.0 && !(s.elapsed >= 200.0 && s.elapsed < 300.0);
    out.axes[1].frequency = out.axes[1].locked ? 1.1 * f0 : 1.0;
    scorer.add(s, out);
  }
  const metrics::PeriodErrors errors = scorer.finish();
  EXPECT_EQ(errors.lock_time.x(), 100.0);
  EXPECT_EQ(errors.lock_time.y(), 50.0);
  EXPECT_TRUE(std::isnan(errors.lock_time.z()));
  // Hops end at samples 9, 19, ... and are scored kSearchDelay (2 samples) later, where the
  // compensator takes them up: 350 of them from 50.1 s to 399.1 s, 100 in 200..300 s.
  EXPECT_DOUBLE_EQ(errors.locked_percent.x(), 100.0);
  EXPECT_DOUBLE_EQ(errors.locked_percent.y(), 100.0 * 250 / 350);
  EXPECT_TRUE(std::isnan(errors.locked_percent.z()));
  // 0.1 Hz is a bin of the truth's 60 s and 30 s windows: its tracker finds it to rounding.
  EXPECT_LT(errors.error_median.x(), 1e-9);
  EXPECT_LT(errors.error_p95.x(), 1e-9);
  EXPECT_NEAR(errors.error_median.y(), 10.0, 1e-9);
  EXPECT_NEAR(errors.error_p95.y(), 10.0, 1e-9);  // only hops while locked count
  EXPECT_TRUE(std::isnan(errors.error_median.z()));
  EXPECT_TRUE(std::isnan(errors.error_p95.z()));
}

namespace
{
/// Two sinusoids of heave, 0.3 m at 0.1 Hz and 0.1 m at 0.17 Hz, at 20 Hz for 900 s, plus white
/// noise of `sigma` m/s^2 on the specific force and a constant bias of 0.05 m/s^2.
std::vector<sim::Sample> twoComponentHeave(double sigma)
{
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, sigma);
  return run(20.0, 900.0, [&](double t, sim::Sample* s) {
    double z = 0.0, a = 0.0;
    for (const auto& [amplitude, frequency] : { std::pair{ 0.3, 0.1 }, std::pair{ 0.1, 0.17 } })
    {
      const double w = 2.0 * M_PI * frequency;
      z += amplitude * std::sin(w * t);
      a -= amplitude * w * w * std::sin(w * t);
    }
    s->truth.wave_position = Vector3(0, 0, z);
    s->truth.position = s->truth.wave_position;
    s->accel = Vector3(0, 0, kGravity + a + 0.05 + noise(rng));
  });
}
}  // namespace

TEST(Metrics, CausalBoundOfANoiseFreeSeaIsNearZero)
{
  // A sum of sinusoids is predicted exactly by a causal FIR from its own acceleration (and the
  // constant bias by the fit's constant).
  const metrics::Errors bound = metrics::causalBound(twoComponentHeave(0.0), kGravity, 20.0, Vector3::Zero());
  EXPECT_LT(bound.wave_rms_percent.z(), 1.0);
}

TEST(Metrics, CausalBoundGrowsWithTheNoise)
{
  const metrics::Errors quiet = metrics::causalBound(twoComponentHeave(0.01), kGravity, 20.0, Vector3::Zero());
  const metrics::Errors noisy = metrics::causalBound(twoComponentHeave(0.1), kGravity, 20.0, Vector3::Zero());
  EXPECT_GT(quiet.wave_rms_percent.z(), 0.0);
  EXPECT_GT(noisy.wave_rms_percent.z(), 2.0 * quiet.wave_rms_percent.z());
  EXPECT_LT(noisy.wave_rms_percent.z(), 100.0);
}
