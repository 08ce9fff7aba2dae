// Each effect's own signature, measured on the simulator's output minus the ideal IMU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sim_test_util.h"

namespace sim = periodic_bias_compensation::sim;
using sim_test::axis;
using sim_test::run;
using sim_test::staticScenario;

namespace
{
sim::EffectSpec effect(const std::string& name, const std::map<std::string, std::vector<double>>& params)
{
  sim::EffectSpec e = sim::defaultEffect(name);
  for (const auto& [key, value] : params)
  {
    e.params[key] = value;
  }
  return sim::completeEffect(e);
}

sim::Scenario shaken(double rate, double duration)
{
  sim::Scenario s = staticScenario(rate, duration);
  s.motion.type = sim::MotionType::kSinusoids;
  s.motion.sinusoids[sim::kSurge] = { 0.5, 0.4, 0.0 };
  s.motion.sinusoids[sim::kHeave] = { 0.3, 0.3, 1.0 };
  s.motion.sinusoids[sim::kRoll] = { 0.2, 0.25, 0.5 };
  s.motion.sinusoids[sim::kPitch] = { 0.1, 0.15, 0.0 };
  s.motion.sinusoids[sim::kYaw] = { 0.3, 0.1, 2.0 };
  return s;
}
}  // namespace

TEST(Effects, NoEffectGivesTheIdealImu)
{
  const sim_test::Errors e = run(shaken(100.0, 10.0));
  for (std::size_t k = 0; k < e.accel.size(); ++k)
  {
    ASSERT_EQ(e.accel[k].norm(), 0.0);
    ASSERT_EQ(e.gyro[k].norm(), 0.0);
  }
}

TEST(Effects, WhiteNoisePsdLevelAndAllanDeviation)
{
  const double n_accel = 0.003;
  const double n_gyro = 2e-4;
  const double fs = 100.0;
  sim::Scenario s = staticScenario(fs, 2000.0);
  s.effects.push_back(effect("white_noise", { { "accel_density", { n_accel } }, { "gyro_density", { n_gyro } } }));
  const sim_test::Errors e = run(s);
  for (int i = 0; i < 3; ++i)
  {
    const std::vector<double> a = axis(e.accel, i);
    const std::vector<double> g = axis(e.gyro, i);
    double level_a = 0.0;
    double level_g = 0.0;
    const std::vector<double> freqs = { 1.0, 7.0, 19.0, 33.0, 45.0 };
    for (const double f : freqs)
    {
      level_a += sim_test::psd(a, fs, f, 1024) / freqs.size();
      level_g += sim_test::psd(g, fs, f, 1024) / freqs.size();
    }
    // One-sided PSD = 2 N^2 (two-sided N^2), flat.
    EXPECT_NEAR(level_a / (2.0 * n_accel * n_accel), 1.0, 0.08) << "axis " << i;
    EXPECT_NEAR(level_g / (2.0 * n_gyro * n_gyro), 1.0, 0.08) << "axis " << i;
    // Allan deviation at 1 s = N, slope -1/2.
    EXPECT_NEAR(sim_test::allanDeviation(a, 100) / n_accel, 1.0, 0.06);
    EXPECT_NEAR(sim_test::allanDeviation(a, 1000) / (n_accel / std::sqrt(10.0)), 1.0, 0.15);
  }
}

TEST(Effects, ConstantBiasIsExactOffset)
{
  sim::Scenario s = shaken(100.0, 10.0);
  s.effects.push_back(
      effect("constant_bias", { { "accel", { 0.02, -0.01, 0.03 } }, { "gyro", { 1e-3, 2e-3, -3e-3 } } }));
  const sim_test::Errors e = run(s);
  for (std::size_t k = 0; k < e.accel.size(); ++k)
  {
    ASSERT_NEAR((e.accel[k] - sim::Vector3(0.02, -0.01, 0.03)).norm(), 0.0, 1e-12);
    ASSERT_NEAR((e.gyro[k] - sim::Vector3(1e-3, 2e-3, -3e-3)).norm(), 0.0, 1e-12);
  }
}

TEST(Effects, BiasRandomWalkAllanSlopeIsPlusHalf)
{
  const double k_density = 1e-4;
  const double fs = 10.0;
  sim::Scenario s = staticScenario(fs, 40000.0);
  s.effects.push_back(
      effect("bias_random_walk", { { "accel_density", { k_density } }, { "gyro_density", { k_density } } }));
  const sim_test::Errors e = run(s);
  double avar10 = 0.0;
  double avar100 = 0.0;
  for (int i = 0; i < 3; ++i)
  {
    for (const std::vector<double>& x : { axis(e.accel, i), axis(e.gyro, i) })
    {
      avar10 += std::pow(sim_test::allanDeviation(x, 100), 2) / 6.0;
      avar100 += std::pow(sim_test::allanDeviation(x, 1000), 2) / 6.0;
    }
  }
  const double slope = 0.5 * std::log10(avar100 / avar10);
  EXPECT_NEAR(slope, 0.5, 0.12);
  // sigma^2(tau) = K^2 tau / 3
  EXPECT_NEAR(avar10 / (k_density * k_density * 10.0 / 3.0), 1.0, 0.3);
}

TEST(Effects, BiasInstabilityAutocorrelationAtCorrelationTime)
{
  const double sigma = 0.01;
  const double tau = 5.0;
  const double fs = 10.0;
  sim::Scenario s = staticScenario(fs, 10000.0);
  s.effects.push_back(
      effect("bias_instability",
             { { "accel_sigma", { sigma } }, { "gyro_sigma", { sigma } }, { "correlation_time", { tau } } }));
  const sim_test::Errors e = run(s);
  double c0 = 0.0;
  double ctau = 0.0;
  double c3tau = 0.0;
  for (int i = 0; i < 3; ++i)
  {
    for (const std::vector<double>& x : { axis(e.accel, i), axis(e.gyro, i) })
    {
      c0 += sim_test::autocovariance(x, 0) / 6.0;
      ctau += sim_test::autocovariance(x, static_cast<std::size_t>(tau * fs)) / 6.0;
      c3tau += sim_test::autocovariance(x, static_cast<std::size_t>(3 * tau * fs)) / 6.0;
    }
  }
  EXPECT_NEAR(c0 / (sigma * sigma), 1.0, 0.1);
  EXPECT_NEAR(ctau / c0, std::exp(-1.0), 0.05);
  EXPECT_NEAR(c3tau / c0, std::exp(-3.0), 0.05);
}

TEST(Effects, PeriodicBiasSpectralLineAtOneOverPeriod)
{
  const double fs = 50.0;
  sim::Scenario s = staticScenario(fs, 700.0);
  s.effects.push_back(effect("periodic_bias", { { "accel_amplitude", { 0.01, 0.0, 0.005 } },
                                                { "accel_period", { 7.0, 7.0, 2.0 } },
                                                { "accel_phase", { 0.4, 0.0, 0.0 } },
                                                { "gyro_amplitude", { 0.0, 1e-3, 0.0 } },
                                                { "gyro_period", { 10.0, 5.0, 10.0 } } }));
  const sim_test::Errors e = run(s);
  const std::vector<double> ax = axis(e.accel, 0);
  EXPECT_NEAR(sim_test::lineAmplitude(ax, fs, 1.0 / 7.0), 0.01, 2e-4);
  EXPECT_LT(sim_test::lineAmplitude(ax, fs, 2.0 / 7.0), 1e-4);
  EXPECT_NEAR(ax[0], 0.01 * std::sin(0.4), 1e-12);
  EXPECT_NEAR(sim_test::lineAmplitude(axis(e.accel, 2), fs, 0.5), 0.005, 1e-4);
  EXPECT_LT(sim_test::lineAmplitude(axis(e.accel, 1), fs, 1.0 / 7.0), 1e-12);
  EXPECT_NEAR(sim_test::lineAmplitude(axis(e.gyro, 1), fs, 0.2), 1e-3, 2e-5);
}

TEST(Effects, ThermalDriftFollowsTemperatureProfile)
{
  sim::Scenario s = staticScenario(1.0, 86400.0);
  s.temperature.enabled = true;
  s.temperature.mean = 25.0;
  s.temperature.amplitude = 8.0;
  s.temperature.period = 86400.0;
  s.effects.push_back(effect("thermal_drift", { { "accel_coefficient", { 1e-3, 0.0, -2e-3 } },
                                                { "gyro_coefficient", { 0.0, 1e-5, 0.0 } },
                                                { "reference_temperature", { 20.0 } } }));
  const sim_test::Errors e = run(s, 1, true);
  double t_min = 1e9;
  double t_max = -1e9;
  for (std::size_t k = 0; k < e.samples.size(); ++k)
  {
    const sim::Sample& smp = e.samples[k];
    ASSERT_TRUE(smp.has_temperature);
    const double expected_t = 25.0 + 8.0 * std::sin(2.0 * M_PI * smp.elapsed / 86400.0);
    ASSERT_NEAR(smp.temperature, expected_t, 1e-9);
    const double dT = smp.temperature - 20.0;
    ASSERT_NEAR(e.accel[k].x(), 1e-3 * dT, 1e-12);
    ASSERT_NEAR(e.accel[k].z(), -2e-3 * dT, 1e-12);
    ASSERT_NEAR(e.gyro[k].y(), 1e-5 * dT, 1e-12);
    t_min = std::min(t_min, smp.temperature);
    t_max = std::max(t_max, smp.temperature);
  }
  EXPECT_NEAR(t_max - t_min, 16.0, 1e-3);
}

TEST(Effects, ScaleFactorMultipliesTheSignal)
{
  sim::Scenario s = shaken(100.0, 10.0);
  s.effects.push_back(
      effect("scale_factor", { { "accel", { 0.01, -0.02, 0.005 } }, { "gyro", { 0.03, 0.0, -0.01 } } }));
  const sim_test::Errors e = run(s, 1, true);
  for (std::size_t k = 0; k < e.samples.size(); ++k)
  {
    sim::Vector3 a;
    sim::Vector3 g;
    sim::idealImu(e.samples[k].truth, s.gravity, &a, &g);
    ASSERT_NEAR((e.accel[k] - a.cwiseProduct(sim::Vector3(0.01, -0.02, 0.005))).norm(), 0.0, 1e-12);
    ASSERT_NEAR((e.gyro[k] - g.cwiseProduct(sim::Vector3(0.03, 0.0, -0.01))).norm(), 0.0, 1e-12);
  }
}

TEST(Effects, MisalignmentCouplesAxes)
{
  sim::Scenario s = staticScenario(100.0, 1.0);
  s.effects.push_back(effect("misalignment", { { "accel", { 0, 0, 0.01, 0, 0, -0.02, 0, 0, 0 } } }));
  const sim_test::Errors e = run(s);
  // At rest, level: z reads g, so gravity leaks into x and y through the coupling terms.
  EXPECT_NEAR(e.accel[0].x(), 0.01 * s.gravity, 1e-12);
  EXPECT_NEAR(e.accel[0].y(), -0.02 * s.gravity, 1e-12);
  EXPECT_NEAR(e.accel[0].z(), 0.0, 1e-12);
}

TEST(Effects, GravityLeakageTiltsReportedOrientation)
{
  const double pitch = 0.01;
  const double roll = -0.02;
  sim::Scenario s = staticScenario(100.0, 1.0);
  s.effects.push_back(effect("gravity_leakage", { { "pitch", { pitch } }, { "roll", { roll } } }));
  const sim_test::Errors e = run(s, 1, true);
  const sim::Sample& smp = e.samples.front();
  EXPECT_EQ(e.accel.front().norm(), 0.0);  // measurements untouched
  // Gravity removed with the reported orientation leaks g * sin(tilt) into the level axes.
  const sim::Vector3 residual = smp.orientation * smp.accel - sim::Vector3(0.0, 0.0, s.gravity);
  const double tilt = std::acos(std::cos(pitch) * std::cos(roll));
  EXPECT_NEAR(residual.head<2>().norm(), s.gravity * std::sin(tilt), 1e-9);
  EXPECT_GT(residual.head<2>().norm(), 0.1);
}

TEST(Effects, LeverArmMatchesDifferentiatedSensorPosition)
{
  const sim::Vector3 r(1.5, -0.8, 2.0);
  const double fs = 1000.0;
  sim::Scenario s = shaken(fs, 8.0);
  s.effects.push_back(effect("lever_arm", { { "offset", { r.x(), r.y(), r.z() } } }));
  const sim_test::Errors e = run(s, 1, true);
  const double h = 1.0 / fs;
  double worst = 0.0;
  double largest = 0.0;
  for (std::size_t k = 1; k + 1 < e.samples.size(); k += 37)
  {
    const auto p = [&](std::size_t j) {
      return sim::Vector3(e.samples[j].truth.position + e.samples[j].truth.attitude * r);
    };
    const sim::Vector3 a_sensor = (p(k + 1) - 2.0 * p(k) + p(k - 1)) / (h * h);
    const sim::Vector3 f = e.samples[k].truth.attitude.conjugate() * (a_sensor + sim::Vector3(0, 0, s.gravity));
    worst = std::max(worst, (f - e.samples[k].accel).norm());
    sim::Vector3 a0;
    sim::Vector3 g0;
    sim::idealImu(e.samples[k].truth, s.gravity, &a0, &g0);
    largest = std::max(largest, (e.samples[k].accel - a0).norm());
    ASSERT_EQ(e.gyro[k].norm(), 0.0);
  }
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(largest, 0.1);  // the effect is large enough to matter
}

TEST(Effects, VibrationLineAliasesWhereExpected)
{
  const double fs = 87.7;
  sim::Scenario s = staticScenario(fs, 200.0);
  s.effects.push_back(effect("vibration", { { "frequency", { 95.0, 20.0 } },
                                            { "accel_amplitude", { 0.2, 0.0, 0.0, 0.0, 0.1, 0.0 } },
                                            { "gyro_amplitude", { 0.0, 0.0, 0.01, 0.0, 0.0, 0.0 } } }));
  const sim_test::Errors e = run(s);
  const std::vector<double> ax = axis(e.accel, 0);
  const double alias = 95.0 - fs;  // 7.3 Hz
  EXPECT_NEAR(sim_test::lineAmplitude(ax, fs, alias), 0.2, 0.005);
  EXPECT_LT(sim_test::lineAmplitude(ax, fs, 12.0), 0.005);  // nothing elsewhere
  EXPECT_NEAR(sim_test::lineAmplitude(axis(e.accel, 1), fs, 20.0), 0.1, 0.003);
  EXPECT_LT(sim_test::lineAmplitude(axis(e.accel, 1), fs, alias), 0.005);
  EXPECT_NEAR(sim_test::lineAmplitude(axis(e.gyro, 2), fs, alias), 0.01, 3e-4);
}

TEST(Effects, VibrationBandwidthGivesLorentzianCoherenceDecay)
{
  // Phase random walk: autocorrelation (1/2) A^2 cos(2 pi f tau) exp(-pi B tau).
  const double fs = 50.0;
  const double f = 7.0;  // whole periods in 1 s and 2 s
  const double bandwidth = 0.2;
  sim::Scenario s = staticScenario(fs, 4000.0);
  s.effects.push_back(
      effect("vibration",
             { { "frequency", { f } }, { "accel_amplitude", { 0.3, 0.0, 0.0 } }, { "bandwidth", { bandwidth } } }));
  const sim_test::Errors e = run(s);
  const std::vector<double> ax = axis(e.accel, 0);
  const double c0 = sim_test::autocovariance(ax, 0);
  EXPECT_NEAR(c0, 0.5 * 0.3 * 0.3, 0.003);
  EXPECT_NEAR(sim_test::autocovariance(ax, 50) / c0, std::exp(-M_PI * bandwidth * 1.0), 0.05);
  EXPECT_NEAR(sim_test::autocovariance(ax, 100) / c0, std::exp(-M_PI * bandwidth * 2.0), 0.05);
  // Peak of the one-sided Lorentzian PSD: (A^2 / 2) * 2 / (pi B).
  EXPECT_NEAR(sim_test::psd(ax, fs, f, 4096) / (0.3 * 0.3 / (M_PI * bandwidth)), 1.0, 0.25);
}

TEST(Effects, QuantizationPutsOutputOnLattice)
{
  const double step = 0.01;
  const double gstep = 1e-3;
  sim::Scenario s = shaken(100.0, 10.0);
  s.effects.push_back(effect("quantization", { { "accel_step", { step } }, { "gyro_step", { gstep } } }));
  const sim_test::Errors e = run(s, 1, true);
  double largest = 0.0;
  for (std::size_t k = 0; k < e.samples.size(); ++k)
  {
    for (int i = 0; i < 3; ++i)
    {
      const double a = e.samples[k].accel[i] / step;
      const double g = e.samples[k].gyro[i] / gstep;
      ASSERT_NEAR(a, std::round(a), 1e-6);
      ASSERT_NEAR(g, std::round(g), 1e-6);
      ASSERT_LE(std::abs(e.accel[k][i]), 0.5 * step + 1e-12);
      largest = std::max(largest, std::abs(e.accel[k][i]));
    }
  }
  EXPECT_GT(largest, 0.4 * step);
}

TEST(Effects, SampleHoldRepeatsReadingsBetweenSensorUpdates)
{
  // A 100 Hz driver polling a 30 Hz sensor: 70 % of the samples repeat their predecessor, the
  // readings change 30 times a second, and a stamp is never repeated.
  const double rate = 100.0, sensor_rate = 30.0;
  sim::Scenario s = shaken(rate, 20.0);
  s.effects.push_back(effect("white_noise", { { "accel_density", { 2e-3 } }, { "gyro_density", { 1e-4 } } }));
  s.effects.push_back(effect("sample_hold", { { "sensor_rate", { sensor_rate } } }));
  const sim_test::Errors held = run(s, 1, true);
  s.effects.pop_back();
  const sim_test::Errors fresh = run(s, 1, true);
  ASSERT_EQ(held.samples.size(), fresh.samples.size());
  int repeated = 0, fresh_repeated = 0;
  for (std::size_t k = 1; k < held.samples.size(); ++k)
  {
    const sim::Sample& a = held.samples[k - 1];
    const sim::Sample& b = held.samples[k];
    const bool same = a.accel == b.accel && a.gyro == b.gyro && a.orientation.coeffs() == b.orientation.coeffs();
    repeated += same ? 1 : 0;
    fresh_repeated += fresh.samples[k - 1].accel == fresh.samples[k].accel ? 1 : 0;
    EXPECT_GT(b.stamp, a.stamp);
    if (!same)
    {
      // A new reading is the sensor's value at that poll, as without the hold.
      EXPECT_EQ(b.accel, fresh.samples[k].accel) << k;
    }
  }
  const double fraction = static_cast<double>(repeated) / (held.samples.size() - 1);
  EXPECT_NEAR(fraction, 1.0 - sensor_rate / rate, 0.01);
  EXPECT_EQ(fresh_repeated, 0);
}

TEST(Effects, SaturationFlatTops)
{
  sim::Scenario s = staticScenario(100.0, 20.0);
  s.motion.type = sim::MotionType::kSinusoids;
  s.motion.sinusoids[sim::kSurge] = { 1.0, 1.0, 0.0 };  // peak 39.5 m/s^2
  s.motion.sinusoids[sim::kRoll] = { 0.5, 1.0, 0.0 };   // peak 3.14 rad/s
  s.effects.push_back(effect("saturation", { { "accel_limit", { 20.0 } }, { "gyro_limit", { 2.0 } } }));
  const sim_test::Errors e = run(s, 1, true);
  int at_limit = 0;
  int run_length = 0;
  int longest = 0;
  double peak = 0.0;
  double gyro_peak = 0.0;
  for (const sim::Sample& smp : e.samples)
  {
    peak = std::max(peak, std::abs(smp.accel.x()));
    gyro_peak = std::max(gyro_peak, std::abs(smp.gyro.x()));
    const bool flat = std::abs(smp.accel.x()) == 20.0;
    at_limit += flat ? 1 : 0;
    run_length = flat ? run_length + 1 : 0;
    longest = std::max(longest, run_length);
  }
  EXPECT_EQ(peak, 20.0);
  EXPECT_EQ(gyro_peak, 2.0);
  EXPECT_GT(at_limit, 100);
  EXPECT_GE(longest, 10);  // flat tops span many samples
}

TEST(Effects, TimestampJitterStatistics)
{
  const double sigma = 2e-3;
  const double offset = 5e-3;
  sim::Scenario s = staticScenario(100.0, 200.0);
  s.effects.push_back(effect("timestamp_jitter", { { "sigma", { sigma } }, { "offset", { offset } } }));
  const sim_test::Errors e = run(s, 1, true);
  std::vector<double> d;
  for (const sim::Sample& smp : e.samples)
  {
    d.push_back(smp.stamp - smp.t);
    ASSERT_NEAR(smp.t, s.start_time + smp.index / s.rate, 1e-9);
  }
  double mean = 0.0;
  double stddev = 0.0;
  sim_test::meanStd(d, &mean, &stddev);
  EXPECT_NEAR(mean, offset, 1e-4);
  EXPECT_NEAR(stddev / sigma, 1.0, 0.05);
  EXPECT_LT(std::abs(sim_test::autocovariance(d, 1)) / (sigma * sigma), 0.05);  // independent
}

TEST(Effects, DropoutsProbabilityAndBurstLength)
{
  const double p = 0.01;
  const double burst = 5.0;
  sim::Scenario s = staticScenario(100.0, 3000.0);
  s.effects.push_back(effect("dropouts", { { "probability", { p } }, { "burst_length", { burst } } }));
  const sim_test::Errors e = run(s, 1, true);
  int dropped = 0;
  int bursts = 0;
  bool previous = false;
  for (const sim::Sample& smp : e.samples)
  {
    dropped += smp.dropped ? 1 : 0;
    bursts += (smp.dropped && !previous) ? 1 : 0;
    previous = smp.dropped;
  }
  const double fraction = static_cast<double>(dropped) / e.samples.size();
  EXPECT_NEAR(fraction / (p / (p + 1.0 / burst)), 1.0, 0.1);
  EXPECT_NEAR(static_cast<double>(dropped) / bursts / burst, 1.0, 0.1);
}

TEST(Effects, StageOrderIsFixed)
{
  // Scale factor applies before the bias whatever the list order: out = (1 + s) in + b.
  sim::Scenario s = staticScenario(10.0, 1.0);
  s.effects.push_back(effect("constant_bias", { { "accel", { 1.0 } } }));
  s.effects.push_back(effect("scale_factor", { { "accel", { 0.1 } } }));
  const sim_test::Errors e = run(s);
  EXPECT_NEAR(e.accel[0].z(), 0.1 * s.gravity + 1.0, 1e-12);
  EXPECT_NEAR(e.accel[0].x(), 1.0, 1e-12);
}
