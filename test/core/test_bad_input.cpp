// Each kind of bad input: a clear status, counted, nothing lost, never a NaN out.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "periodic_bias_compensation/core/compensator.h"
#include "synthetic.h"

namespace pbc = periodic_bias_compensation;
using pbc::Compensator;
using pbc::CompensatorConfig;
using pbc::CompensatorOutput;
using pbc::SampleStatus;
using pbc::Vector3;

namespace
{
bool finiteOutput(const CompensatorOutput& o)
{
  bool ok = o.position_filtered.allFinite() && o.velocity_filtered.allFinite() && o.position_wave.allFinite() &&
            o.velocity_wave.allFinite() && o.acceleration_level.allFinite() && o.position_variance.allFinite() &&
            o.velocity_variance.allFinite() && o.wave_position_variance.allFinite() &&
            o.orientation.coeffs().allFinite();
  for (const auto& a : o.axes)
    ok = ok && std::isfinite(a.constant_bias) && std::isfinite(a.periodic_bias) && std::isfinite(a.frequency) &&
         std::isfinite(a.d_v) && std::isfinite(a.d_p);
  return ok;
}

/// Feeds `count` good samples from the record starting at `first`, checking every output.
void feed(Compensator& c, const pbc::test::ShakeRecord& r, std::size_t first, std::size_t count,
          double time_shift = 0.0)
{
  CompensatorOutput out;
  for (std::size_t k = first; k < first + count && k < r.samples.size(); ++k)
  {
    pbc::ImuSample s = r.samples[k];
    s.t += time_shift;
    const SampleStatus status = c.addSample(s, &out);
    ASSERT_TRUE(status == SampleStatus::kAccepted || status == SampleStatus::kGapReset ||
                status == SampleStatus::kResetBackwards);
    ASSERT_TRUE(finiteOutput(out)) << "sample " << k;
  }
}

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

pbc::test::ShakeRecord record()
{
  pbc::test::Shake shake;
  shake.duration = 40.0;
  return pbc::test::makeShake(shake);
}
}  // namespace

TEST(BadInput, NonFiniteFieldsAreRejectedAndCounted)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 1500);
  const Vector3 bias_before = c.constantBias();
  int n = 0;
  for (int field = 0; field < 4; ++field)
    for (double bad : { kNaN, kInf, -kInf })
    {
      pbc::ImuSample s = r.samples[1500];
      if (field == 0)
        s.specific_force.y() = bad;
      else if (field == 1)
        s.angular_rate.z() = bad;
      else if (field == 2)
        s.orientation.w() = bad;
      else
        s.t = bad;
      CompensatorOutput out;
      EXPECT_EQ(c.addSample(s, &out), SampleStatus::kRejectedNonFinite) << "field " << field;
      ++n;
    }
  EXPECT_EQ(c.counters().rejected_non_finite, static_cast<unsigned>(n));
  EXPECT_EQ(c.constantBias(), bias_before) << "a rejected sample changes nothing";
  feed(c, r, 1500, 500);
  EXPECT_EQ(c.counters().accepted, 2000u);
}

TEST(BadInput, NonUnitQuaternionsAreRejectedAllZerosMeansNone)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 100);
  pbc::ImuSample s = r.samples[100];
  s.orientation = pbc::Quaternion(1.2, 0, 0, 0);
  EXPECT_EQ(c.addSample(s, nullptr), SampleStatus::kRejectedBadQuaternion);
  s.orientation = pbc::Quaternion(0.5, 0, 0, 0);
  EXPECT_EQ(c.addSample(s, nullptr), SampleStatus::kRejectedBadQuaternion);
  // Slightly off unit (float rounding in a driver) is normalised and accepted.
  s.orientation = pbc::Quaternion(1.0 + 1e-4, 0, 0, 0);
  EXPECT_EQ(c.addSample(s, nullptr), SampleStatus::kAccepted);
  EXPECT_EQ(c.counters().rejected_bad_quaternion, 2u);
  // All zeros, as IMUs without an AHRS send it without the covariance -1 flag: no orientation,
  // the sample is used (levelled as one without orientation), and counted.
  for (std::size_t k = 101; k < 400; ++k)
  {
    pbc::ImuSample z = r.samples[k];
    z.orientation = pbc::Quaternion(0, 0, 0, 0);
    CompensatorOutput out;
    ASSERT_EQ(c.addSample(z, &out), SampleStatus::kAccepted) << k;
    ASSERT_TRUE(finiteOutput(out));
  }
  EXPECT_EQ(c.counters().zero_orientation, 299u);
  EXPECT_EQ(c.counters().rejected_bad_quaternion, 2u);
}

TEST(BadInput, AccelerationInGIsRecognised)
{
  // A driver publishing g instead of m/s^2 (REP-145): the mean specific force says so after
  // kUnitsSettle; in m/s^2 it is plausible; 30 m/s^2 at rest is neither.
  for (const auto& [scale, units] :
       { std::pair{ 1.0 / pbc::kStandardGravity, pbc::ForceUnits::kLooksLikeG },
         std::pair{ 1.0, pbc::ForceUnits::kPlausible }, std::pair{ 3.0, pbc::ForceUnits::kImplausible } })
  {
    const auto r = record();
    Compensator c;
    for (std::size_t k = 0; k < 200; ++k)
    {
      pbc::ImuSample s = r.samples[k];
      s.specific_force *= scale;
      c.addSample(s, nullptr);
      if (k == 10)
      {
        EXPECT_EQ(c.forceUnits(), pbc::ForceUnits::kUnknown);
      }
    }
    EXPECT_EQ(c.forceUnits(), units) << "scale " << scale;
    EXPECT_NEAR(c.meanSpecificForce(), scale * pbc::kStandardGravity, 0.05 * scale * pbc::kStandardGravity);
  }
}

TEST(BadInput, DuplicatedStampIsDropped)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 200);
  EXPECT_EQ(c.addSample(r.samples[199], nullptr), SampleStatus::kRejectedDuplicate);
  EXPECT_EQ(c.counters().rejected_duplicate, 1u);
  feed(c, r, 200, 100);
}

TEST(BadInput, StampsGoingBackwardsResetCleanly)
{
  // A bag replayed with --loop: the jump back is confirmed by kConfirmSamples samples (held until
  // then, then processed), and the second pass gives what a fresh compensator gives, with and
  // without orientation in the messages (then the level is measured again too).
  for (bool with_orientation : { true, false })
  {
    pbc::test::Shake shake;
    shake.duration = 40.0;
    shake.with_orientation = with_orientation;
    const auto r = pbc::test::makeShake(shake);
    Compensator looped, fresh;
    feed(looped, r, 0, r.samples.size());
    CompensatorOutput out_looped, out_fresh;
    for (int k = 0; k + 1 < pbc::kConfirmSamples; ++k)
    {
      EXPECT_EQ(looped.addSample(r.samples[k], &out_looped), SampleStatus::kHeld);
      fresh.addSample(r.samples[k], &out_fresh);
    }
    EXPECT_EQ(looped.counters().resets_backwards, 0u) << "not confirmed yet";
    const std::size_t last_held = pbc::kConfirmSamples - 1;
    EXPECT_EQ(looped.addSample(r.samples[last_held], &out_looped), SampleStatus::kResetBackwards);
    fresh.addSample(r.samples[last_held], &out_fresh);
    EXPECT_EQ(looped.counters().resets_backwards, 1u);
    EXPECT_EQ(looped.counters().timing_glitches, 0u);
    for (std::size_t k = last_held + 1; k < r.samples.size(); ++k)
    {
      looped.addSample(r.samples[k], &out_looped);
      fresh.addSample(r.samples[k], &out_fresh);
    }
    EXPECT_NEAR((out_looped.position_filtered - out_fresh.position_filtered).norm(), 0.0, 1e-12);
    EXPECT_NEAR((out_looped.position_wave - out_fresh.position_wave).norm(), 0.0, 1e-12);
  }
}

TEST(BadInput, LongGapResetsTheIntegrationButKeepsTheBias)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 2000);
  ASSERT_TRUE(c.calibrated());
  const Vector3 bias = c.constantBias();
  CompensatorOutput out;
  // 5 s of missing samples, far over max_gap: confirmed by kConfirmSamples samples.
  for (int k = 0; k < pbc::kConfirmSamples; ++k)
  {
    pbc::ImuSample late = r.samples[2000 + k];
    late.t += 5.0;
    EXPECT_EQ(c.addSample(late, &out), k + 1 < pbc::kConfirmSamples ? SampleStatus::kHeld : SampleStatus::kGapReset);
  }
  EXPECT_EQ(c.counters().gap_resets, 1u);
  EXPECT_TRUE(c.calibrated());
  EXPECT_NEAR((c.constantBias() - bias).norm(), 0.0, 1e-4) << "four samples' worth of bias tracking at most";
  // Four steps of the shaken motion since the gap (at most 0.5 x 0.39 m/s^2 x (4 / 87.7 s)^2).
  EXPECT_LT(out.position_filtered.norm(), 5e-4) << "integration restarts from the gap";
  feed(c, r, 2000 + pbc::kConfirmSamples, 500, 5.0);
}

TEST(BadInput, LoneTimingGlitchesAreDroppedNotAReset)
{
  // Common driver glitches, each alone in the stream: a stamp 5 s in the past, a stamp of 0, one
  // 5 s in the future, one 1 ms after its predecessor. Each is dropped and counted; the estimate
  // afterwards is the same as that of the stream with that sample missing.
  const auto r = record();
  struct Glitch
  {
    const char* name;
    double stamp;
    SampleStatus status;
  };
  for (const Glitch& g :
       { Glitch{ "5 s in the past", r.samples[2000].t - 5.0, SampleStatus::kHeld },
         Glitch{ "stamped 0", 0.0, SampleStatus::kHeld },
         Glitch{ "5 s in the future", r.samples[2000].t + 5.0, SampleStatus::kHeld },
         Glitch{ "1 ms after its predecessor", r.samples[1999].t + 0.001, SampleStatus::kRejectedEarly } })
  {
    Compensator glitched, clean;
    feed(glitched, r, 0, 2000);
    feed(clean, r, 0, 2000);
    pbc::ImuSample bad = r.samples[2000];
    bad.t = g.stamp;
    EXPECT_EQ(glitched.addSample(bad, nullptr), g.status) << g.name;
    CompensatorOutput out_glitched, out_clean;
    for (std::size_t k = 2001; k < r.samples.size(); ++k)
    {
      ASSERT_EQ(glitched.addSample(r.samples[k], &out_glitched), SampleStatus::kAccepted) << g.name;
      clean.addSample(r.samples[k], &out_clean);
    }
    EXPECT_EQ(glitched.counters().timing_glitches, 1u) << g.name;
    EXPECT_EQ(glitched.counters().resets_backwards + glitched.counters().gap_resets, 0u) << g.name;
    EXPECT_NEAR(glitched.counters().sample_rate, 87.7, 1e-6) << g.name;
    EXPECT_TRUE(glitched.calibrated()) << g.name;
    EXPECT_NEAR((glitched.constantBias() - clean.constantBias()).norm(), 0.0, 1e-9) << g.name;
    EXPECT_NEAR((out_glitched.position_filtered - out_clean.position_filtered).norm(), 0.0, 1e-9) << g.name;
    EXPECT_NEAR((out_glitched.position_wave - out_clean.position_wave).norm(), 0.0, 1e-9) << g.name;
  }
}

TEST(BadInput, ShortGapIsIntegratedAcross)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 2000);
  // Ten dropped samples (0.11 s) stay under max_gap: integrated across with the longer step.
  feed(c, r, 2010, 1000);
  EXPECT_EQ(c.counters().gap_resets, 0u);
}

TEST(BadInput, ChangedSampleRateIsDetectedAndFollowed)
{
  // 87.7 Hz for 20 s, then every other sample (43.85 Hz): the rate estimate follows and the
  // period is found again; outputs stay finite and the wave is still tracked.
  pbc::test::Shake shake;
  shake.duration = 60.0;
  const auto r = pbc::test::makeShake(shake);
  Compensator c;
  CompensatorOutput out;
  double error = 0.0, truth = 0.0;
  for (std::size_t k = 0; k < r.samples.size(); ++k)
  {
    if (k > 1754 && k % 2 == 1)
      continue;
    c.addSample(r.samples[k], &out);
    ASSERT_TRUE(finiteOutput(out));
    if (r.samples[k].t - r.samples[0].t > 45.0)
    {
      error += std::pow(out.position_wave.x() - r.position[k].x(), 2);
      truth += std::pow(r.position[k].x(), 2);
    }
  }
  EXPECT_GE(c.counters().rate_changes, 1u);
  EXPECT_NEAR(c.counters().sample_rate, 43.85, 2.0);
  EXPECT_LT(std::sqrt(error / truth), 0.10);
}

TEST(BadInput, NoOrientationUsesTheLevelFromCalibration)
{
  // The same motion without orientation, sensor tilted by 3 degrees about x: the level is found
  // from the calibration window's mean specific force and the wave is still tracked (with
  // gyro_attitude off: one level frame; test_gyro_attitude has the gyro's).
  pbc::test::Shake shake;
  shake.with_orientation = false;
  auto r = pbc::test::makeShake(shake);
  const pbc::Quaternion tilt(Eigen::AngleAxisd(3.0 * M_PI / 180.0, Vector3::UnitX()));
  for (auto& s : r.samples)
    s.specific_force = tilt.inverse() * s.specific_force;
  CompensatorConfig config;
  config.gyro_attitude = false;
  Compensator c(config);
  CompensatorOutput out;
  double error = 0.0, truth = 0.0;
  for (std::size_t k = 0; k < r.samples.size(); ++k)
  {
    ASSERT_EQ(c.addSample(r.samples[k], &out), SampleStatus::kAccepted);
    ASSERT_TRUE(finiteOutput(out));
    if (r.samples[k].t - r.samples[0].t > 20.0)
    {
      error += std::pow(out.position_wave.x() - r.position[k].x(), 2);
      truth += std::pow(r.position[k].x(), 2);
    }
  }
  EXPECT_NEAR(c.levelOrientation().angularDistance(tilt), 0.0, 0.01);
  EXPECT_LT(std::sqrt(error / truth), 0.10);
  EXPECT_LT(out.position_filtered.norm(), 0.10);
}

TEST(BadInput, InvalidConfigurationIsRefusedAndTheEstimateKept)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 2500);
  const CompensatorConfig before = c.config();
  CompensatorConfig bad = before;
  bad.gains[1].alpha_v = 2.5;
  std::string why;
  EXPECT_FALSE(c.setConfig(bad, &why));
  EXPECT_NE(why.find("alpha_v_y"), std::string::npos) << why;
  bad = before;
  bad.max_frequency = bad.min_frequency / 2;
  EXPECT_FALSE(c.setConfig(bad, &why));
  EXPECT_NE(why.find("max_frequency"), std::string::npos) << why;
  EXPECT_EQ(c.config().gains[1].alpha_v, before.gains[1].alpha_v);
  EXPECT_THROW(Compensator{ bad }, std::invalid_argument);
  // The running estimate goes on as if nothing had been asked.
  Compensator reference;
  feed(reference, r, 0, 2500);
  CompensatorOutput a, b;
  for (std::size_t k = 2500; k < r.samples.size(); ++k)
  {
    c.addSample(r.samples[k], &a);
    reference.addSample(r.samples[k], &b);
  }
  EXPECT_EQ(a.position_wave, b.position_wave);
}

TEST(BadInput, AbsurdFiniteForceOrRateIsRejectedAndCounted)
{
  // F3 (docs/reliability.md): a finite specific force of 1e232 m/s^2 used to be integrated and
  // overflow the state. Any caller now gets it refused by the core, the estimate unharmed.
  const auto r = record();
  Compensator c, reference;
  feed(c, r, 0, 1500);
  feed(reference, r, 0, 1500);
  int n = 0;
  for (int field = 0; field < 4; ++field)
  {
    pbc::ImuSample s = r.samples[1500];
    s.t -= 0.5 / 87.7;  // between two good samples
    if (field == 0)
      s.specific_force.z() = -3.9e232;
    else if (field == 1)
      s.specific_force.x() = 2000.5;
    else if (field == 2)
      s.angular_rate.y() = 1e300;
    else
      s.angular_rate.x() = -100.5;
    CompensatorOutput out;
    EXPECT_EQ(c.addSample(s, &out), SampleStatus::kRejectedOutOfRange) << "field " << field;
    ++n;
  }
  EXPECT_EQ(c.counters().rejected_out_of_range, static_cast<unsigned>(n));
  EXPECT_EQ(c.counters().accepted, reference.counters().accepted);
  CompensatorOutput a, b;
  for (std::size_t k = 1500; k < r.samples.size(); ++k)
  {
    ASSERT_EQ(c.addSample(r.samples[k], &a), SampleStatus::kAccepted);
    reference.addSample(r.samples[k], &b);
  }
  EXPECT_EQ(a.position_wave, b.position_wave);
  EXPECT_EQ(a.position_filtered, b.position_filtered);
  // The limits themselves are accepted.
  pbc::ImuSample edge = r.samples.back();
  edge.t += 1.0 / 87.7;
  edge.specific_force.x() = pbc::kMaxSpecificForce;
  edge.angular_rate.z() = -pbc::kMaxAngularRate;
  EXPECT_EQ(c.addSample(edge, &a), SampleStatus::kAccepted);
}

TEST(BadInput, AbsurdConstantBiasIsRefused)
{
  // F8 and F8b: the fuzzer's setConstantBias(-1.8e298) and (-2.5e260) were accepted (only
  // non-finite values were refused) and the next output overflowed.
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 1500);
  const Vector3 before = c.constantBias();
  EXPECT_FALSE(c.setConstantBias(Vector3(-0.06, -1.8e298, -0.08)));
  EXPECT_FALSE(c.setConstantBias(Vector3(-2.5e260, 4.7e-307, -0.1)));
  EXPECT_FALSE(c.setConstantBias(Vector3(0.0, 0.0, pbc::kMaxConstantBias + 0.5)));
  EXPECT_EQ(c.constantBias(), before);
  feed(c, r, 1500, 500);
  EXPECT_TRUE(c.setConstantBias(Vector3(0.1, -0.2, pbc::kMaxConstantBias)));
  feed(c, r, 2000, 500);
}

namespace
{
/// Paper-mode run on a 1 Hz surge oscillation sampled at L samples per period, the same gains on
/// every axis. Returns how much the largest |position| (filtered or wave) grew over the last
/// 100 s against the 100 s before (Inf if an output was not finite): an unstable comb loop grows
/// exponentially (x1e3 and more per 100 s, then overflows); integrated noise and bias residuals
/// (paper mode bounds neither) grow like t^1.5..t^2, less than x2.3 from 200 to 300 s.
/// *short_flag: an output was flagged period_too_short.
double paperGrowth(int samples_per_period, const pbc::AxisGains& gains, bool* short_flag)
{
  pbc::test::Shake shake;
  shake.rate = samples_per_period * 1.0;
  shake.frequency = Vector3(1.0, 1.0, 1.0);
  shake.amplitude = Vector3(0.1, 0.05, 0.02);
  shake.duration = 300.0;
  const auto r = pbc::test::makeShake(shake);
  CompensatorConfig config;
  config.mode = pbc::Mode::kPaper;
  config.gains = { gains, gains, gains };
  Compensator c(config);
  CompensatorOutput out;
  double middle = 0.0, last = 0.0;
  *short_flag = false;
  for (const auto& s : r.samples)
  {
    c.addSample(s, &out);
    if (!finiteOutput(out))
      return std::numeric_limits<double>::infinity();
    const double size = std::max(out.position_filtered.norm(), out.position_wave.norm());
    const double t = s.t - r.samples.front().t;
    (t < 200.0 ? middle : last) = std::max(t < 100.0 ? 0.0 : (t < 200.0 ? middle : last), size);
    for (const auto& a : out.axes)
      *short_flag = *short_flag || a.period_too_short;
  }
  std::printf("L %d gains %.2f %.2f %.2f %.2f: largest |position| %.3g m at 100-200 s, %.3g m at 200-300 s\n",
              samples_per_period, gains.alpha_v, gains.alpha_p, gains.beta_v, gains.beta_p, middle, last);
  return last / middle;
}
}  // namespace

TEST(BadInput, PaperModeShortPeriodSwitchesTheCorrectionOffInsteadOfDiverging)
{
  // F5: alpha_p 1.52, beta_p 10.4 (accepted by validate) diverged to Inf at L ~ 2.3 samples. At
  // L = 2 the comb loop is linear and stable only for |alpha/2 - beta/4| < 1; under
  // kMinPaperPeriod the correction is now off (flagged), from it on every corner of the accepted
  // gains stays bounded (the homogeneous loop was scanned over alpha 0..1.99, beta 0..12 for L
  // = 2..40, 50, 100, 200: docs/reliability.md).
  bool short_flag = false;
  const pbc::AxisGains f5{ 1.0, 1.52, 8.7, 10.4 };
  for (int l = 2; l < pbc::kMinPaperPeriod; ++l)
  {
    EXPECT_LT(paperGrowth(l, f5, &short_flag), 3.0) << "L = " << l;
    EXPECT_TRUE(short_flag) << "L = " << l;
  }
  for (int l = pbc::kMinPaperPeriod; l <= pbc::kMinPaperPeriod + 4; ++l)
    for (double alpha : { 0.0, 1.0, 1.99 })
      for (double beta : { 0.0, 6.0, 12.0 })
      {
        EXPECT_LT(paperGrowth(l, pbc::AxisGains{ alpha, alpha, beta, beta }, &short_flag), 3.0)
            << "L = " << l << ", alpha " << alpha << ", beta " << beta;
        EXPECT_FALSE(short_flag) << "L = " << l;
      }
}

TEST(BadInput, OrientationLostMidRunLevelsWithTheMeanAttitude)
{
  // F4: when orientation stopped mid-run, the level came from the one sample at that moment
  // (its gravity direction, wave acceleration and instantaneous roll included). The hull here
  // lists 5 degrees and rolls +-4 degrees with the 8 s waves; orientation stops at a roll
  // extreme. The level must be the mean attitude, not the instantaneous one (gyro_attitude off:
  // with it the gyro carries the last orientation on, test_gyro_attitude).
  const double rate = 50.0, list = 5.0 * M_PI / 180.0, roll = 4.0 * M_PI / 180.0, w = 2.0 * M_PI / 8.0;
  CompensatorConfig config;
  config.gyro_attitude = false;
  Compensator c(config);
  CompensatorOutput out;
  const int cut = static_cast<int>(122.0 * rate);  // 122 s = 15.25 periods: roll at its maximum
  for (int k = 0; k < cut + 200; ++k)
  {
    const double t = 1000.0 + k / rate;
    const pbc::Quaternion q(Eigen::AngleAxisd(list + roll * std::sin(w * t - w * 1000.0), Vector3::UnitX()));
    pbc::ImuSample s;
    s.t = t;
    // Sway of 0.5 m with the waves, gravity, in the sensor frame.
    const Vector3 level_force(0.0, -0.5 * w * w * std::sin(w * (t - 1000.0)), pbc::kStandardGravity);
    s.specific_force = q.inverse() * level_force;
    s.has_orientation = k < cut;
    s.orientation = q;
    ASSERT_EQ(c.addSample(s, &out), SampleStatus::kAccepted);
    ASSERT_TRUE(finiteOutput(out));
  }
  const pbc::Quaternion mean(Eigen::AngleAxisd(list, Vector3::UnitX()));
  EXPECT_EQ(c.levelSource(), pbc::LevelSource::kAttitudeBeforeLoss);
  EXPECT_LT(c.levelOrientation().angularDistance(mean) * 180.0 / M_PI, 0.3);
}

TEST(BadInput, SlowImuAgainstAShortDriftConstantStaysBounded)
{
  // F9 (fuzz_compensator, long run): samples 0.59 s apart with drift_time_constant 0.5 s made the
  // slow-motion observer's Euler step unstable: the constant bias grew x7 per sample to 1e154.
  CompensatorConfig config;
  config.drift_time_constant = 0.5;
  config.calibration_duration = 3.0;
  config.max_gap = 2.0;
  pbc::test::Shake shake;
  shake.rate = 1.0 / 0.5883;
  shake.frequency = Vector3(0.17, 0.17, 0.17);
  shake.amplitude = Vector3(0.5, 0.3, 0.2);
  shake.duration = 300.0;
  const auto r = pbc::test::makeShake(shake);
  Compensator c(config);
  CompensatorOutput out;
  for (const auto& s : r.samples)
  {
    ASSERT_EQ(c.addSample(s, &out), SampleStatus::kAccepted);
    ASSERT_TRUE(finiteOutput(out)) << "t = " << s.t;
    // Bounded by the shake's acceleration (0.57 m/s^2 on x): at this drift_time_constant the
    // observer's bias follows a 0.17 Hz motion that is not locked.
    ASSERT_LT(c.constantBias().norm(), 2.0) << "t = " << s.t;
  }
}
