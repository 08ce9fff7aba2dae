#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/lever_arm.h"
#include "synthetic.h"

namespace pbc = periodic_bias_compensation;
using pbc::Compensator;
using pbc::CompensatorConfig;
using pbc::CompensatorOutput;
using pbc::Mode;
using pbc::SampleStatus;
using pbc::Vector3;

namespace
{
struct RunResult
{
  Vector3 final_filtered{ 0, 0, 0 };  ///< |filtered position - true slow position (0)| at the end [m]
  Vector3 wave_rms_error{ 0, 0, 0 };  ///< RMS(wave - truth) after 20 s [m]
  Vector3 wave_rms_truth{ 0, 0, 0 };  ///< RMS(truth) after 20 s [m]
  Vector3 raw_final{ 0, 0, 0 };       ///< plain double integration of the level acceleration [m]
  bool finite = true;
};

RunResult run(const pbc::test::ShakeRecord& record, const CompensatorConfig& config)
{
  Compensator compensator(config);
  RunResult r;
  CompensatorOutput out;
  Vector3 v = Vector3::Zero(), p = Vector3::Zero();
  int counted = 0;
  for (std::size_t k = 0; k < record.samples.size(); ++k)
  {
    const auto status = compensator.addSample(record.samples[k], &out);
    EXPECT_EQ(status, SampleStatus::kAccepted);
    r.finite &= out.position_filtered.allFinite() && out.position_wave.allFinite();
    if (k > 0)
    {
      const double dt = record.samples[k].t - record.samples[k - 1].t;
      v += (record.samples[k].specific_force - Vector3(0, 0, pbc::kStandardGravity)) * dt;
      p += v * dt;
    }
    if (record.samples[k].t - record.samples.front().t >= 20.0)
    {
      const Vector3 e = out.position_wave - record.position[k];
      r.wave_rms_error += e.cwiseProduct(e);
      r.wave_rms_truth += record.position[k].cwiseProduct(record.position[k]);
      ++counted;
    }
  }
  r.final_filtered = out.position_filtered.cwiseAbs();
  r.wave_rms_error = (r.wave_rms_error / counted).cwiseSqrt();
  r.wave_rms_truth = (r.wave_rms_truth / counted).cwiseSqrt();
  r.raw_final = p.cwiseAbs();
  return r;
}

CompensatorConfig modeConfig(Mode mode)
{
  CompensatorConfig config;
  config.mode = mode;
  return config;
}
}  // namespace

TEST(Compensator, ConstantBiasAtRestVanishesInBothModes)
{
  pbc::test::Shake rest;
  rest.amplitude.setZero();
  for (Mode mode : { Mode::kPaper, Mode::kDefault })
  {
    CompensatorConfig config = modeConfig(mode);
    config.assume_static_calibration = true;
    const RunResult r = run(pbc::test::makeShake(rest), config);
    ASSERT_TRUE(r.finite);
    EXPECT_GT(r.raw_final.x(), 20.0) << "the bias must give tens of metres of raw drift";
    // What is left is the noise's double integral: centimetres in default mode, metres in the
    // paper's open-loop constant compensation when no period is found.
    EXPECT_LT(r.final_filtered.maxCoeff(), mode == Mode::kDefault ? 0.05 : 3.0) << pbc::toString(mode);
  }
}

TEST(Compensator, DefaultModeMeetsTheBenchTargetsCausally)
{
  // Bench recordings: shaken at 0.3-0.6 Hz by 2-10 cm, low-cost bias and noise, 87.7 Hz, 60 s,
  // moving from the first sample (no still period). Targets: filtered within 6 cm
  // of the true slow motion (zero) after 60 s, wave within 10 % RMS after 20 s.
  int cases = 0;
  for (double f : { 0.3, 0.443, 0.6 })
    for (double amplitude : { 0.02, 0.05, 0.10 })
      for (unsigned seed : { 1u, 2u })
      {
        pbc::test::Shake shake;
        shake.frequency = Vector3(f, f * 1.07, f);
        // Every axis inside the specified 2-10 cm (smaller motions: docs/algorithm.md, limits).
        shake.amplitude = Vector3(amplitude, std::max(0.02, 0.5 * amplitude), 0.02);
        shake.seed = seed;
        const RunResult r = run(pbc::test::makeShake(shake), modeConfig(Mode::kDefault));
        ASSERT_TRUE(r.finite);
        for (int i = 0; i < 3; ++i)
        {
          EXPECT_LT(r.final_filtered[i], 0.06) << "f=" << f << " A=" << amplitude << " seed=" << seed << " axis " << i;
          EXPECT_LT(r.wave_rms_error[i], 0.10 * r.wave_rms_truth[i])
              << "f=" << f << " A=" << amplitude << " seed=" << seed << " axis " << i << " truth rms "
              << r.wave_rms_truth[i];
        }
        ++cases;
      }
  EXPECT_EQ(cases, 18);
}

TEST(Compensator, PaperScenarioOrdersOfMagnitude)
{
  // The paper's experiments: the constant bias is calibrated on one run at rest (Sec. 4.1) and
  // applied to a second run at rest (Sec. 4.2) and to a shaken run (Sec. 4.3).
  pbc::test::Shake rest;
  rest.amplitude.setZero();
  CompensatorConfig constant_only = modeConfig(Mode::kPaper);
  constant_only.assume_static_calibration = true;
  constant_only.enable_periodic = false;
  Compensator calibration_run(constant_only);
  for (const auto& s : pbc::test::makeShake(rest).samples)
    calibration_run.addSample(s, nullptr);
  ASSERT_TRUE(calibration_run.calibrated());

  // Total position (filtered + wave) against the true displacement: RMS after 20 s and at the end.
  auto evaluate = [&](const pbc::test::ShakeRecord& record, CompensatorConfig config, bool use_calibration) {
    Compensator c(config);
    if (use_calibration)
      c.setConstantBias(calibration_run.constantBias());
    CompensatorOutput out;
    Vector3 sum = Vector3::Zero();
    int n = 0;
    for (std::size_t k = 0; k < record.samples.size(); ++k)
    {
      c.addSample(record.samples[k], &out);
      if (record.samples[k].t - record.samples.front().t >= 20.0)
      {
        const Vector3 e = out.position_filtered + out.position_wave - record.position[k];
        sum += e.cwiseProduct(e);
        ++n;
      }
    }
    return std::make_pair((out.position_filtered + out.position_wave - record.position.back()).cwiseAbs().eval(),
                          (sum / n).cwiseSqrt().eval());
  };

  rest.seed = 11;
  const auto at_rest = pbc::test::makeShake(rest);
  pbc::test::Shake shake;
  shake.amplitude = Vector3(0.05, 0.03, 0.02);
  shake.seed = 7;
  const auto shaken = pbc::test::makeShake(shake);

  const RunResult raw = run(at_rest, constant_only);
  const auto constant_at_rest = evaluate(at_rest, constant_only, true);
  const auto constant_shaken = evaluate(shaken, constant_only, true);
  const auto periodic = evaluate(shaken, modeConfig(Mode::kPaper), true);
  const auto ours = evaluate(shaken, modeConfig(Mode::kDefault), false);
  for (int i = 0; i < 3; ++i)
  {
    std::printf(
        "axis %d after 60 s: raw %.2f m | constant at rest %.3f m | shaken: constant %.3f m, "
        "periodic (paper) %.4f m (rms %.4f), default %.4f m (rms %.4f)\n",
        i, raw.raw_final[i], constant_at_rest.first[i], constant_shaken.first[i], periodic.first[i], periodic.second[i],
        ours.first[i], ours.second[i]);
    EXPECT_GT(raw.raw_final[i], 10.0) << "tens of metres of raw drift";
    EXPECT_GT(raw.raw_final[i], 5.0 * constant_at_rest.first[i]) << "raw >> constant";
    EXPECT_GT(constant_shaken.first[i], 10.0 * periodic.first[i]) << "constant >> periodic";
    EXPECT_LT(periodic.first[i], 0.10) << "periodic compensation leaves centimetres";
    EXPECT_LT(ours.second[i], periodic.second[i]) << "the default mode beats paper mode";
  }
}

TEST(Compensator, PeriodFollowsADriftingEncounterFrequency)
{
  // The encounter frequency moves from 0.40 to 0.52 Hz over 120 s (a ship turning into the
  // waves): the tracked frequency and the wave output must follow, in both modes.
  pbc::test::Shake shake;
  shake.duration = 120.0;
  shake.frequency = Vector3(0.40, 0.40, 0.40);
  shake.chirp = 0.001;
  const auto record = pbc::test::makeShake(shake);
  for (Mode mode : { Mode::kDefault, Mode::kPaper })
  {
    Compensator c(modeConfig(mode));
    CompensatorOutput out;
    double error = 0.0, truth = 0.0;
    for (std::size_t k = 0; k < record.samples.size(); ++k)
    {
      c.addSample(record.samples[k], &out);
      const double t = record.samples[k].t - record.samples[0].t;
      if (t > 60.0)
      {
        error += std::pow(out.position_wave.x() - record.position[k].x(), 2);
        truth += std::pow(record.position[k].x(), 2);
      }
    }
    // A 30 s window centred 15 s back sees the frequency of 15 s ago: 0.505 Hz at the end.
    EXPECT_NEAR(out.axes[0].frequency, 0.52 - 0.015, 0.01) << pbc::toString(mode);
    if (mode == Mode::kDefault)
    {
      EXPECT_LT(std::sqrt(error / truth), 0.10);
    }
  }
}

TEST(Compensator, PaperGainLimits)
{
  // validate() accepts 0 <= alpha < 2 and 0 <= beta <= 12: at the corners of that range the
  // paper loop stays bounded on the shaken run; just outside, the configuration is refused.
  pbc::test::Shake shake;
  shake.amplitude = Vector3(0.05, 0.03, 0.02);
  const auto record = pbc::test::makeShake(shake);
  for (double alpha : { 0.0, 1.0, 1.99 })
    for (double beta : { 0.0, 6.0, 12.0 })
    {
      CompensatorConfig config = modeConfig(Mode::kPaper);
      for (auto& g : config.gains)
        g = { alpha, alpha, beta, beta };
      std::string why;
      ASSERT_TRUE(config.validate(&why)) << why;
      const RunResult r = run(record, config);
      ASSERT_TRUE(r.finite);
      EXPECT_LT(r.final_filtered.maxCoeff(), 50.0) << "alpha " << alpha << " beta " << beta;
    }
  CompensatorConfig config = modeConfig(Mode::kPaper);
  std::string why;
  config.gains[0].alpha_p = 2.0;
  EXPECT_FALSE(config.validate(&why));
  EXPECT_NE(why.find("alpha_p_x = 2 is out of range"), std::string::npos) << why;
  config = modeConfig(Mode::kPaper);
  config.gains[2].beta_v = 12.5;
  EXPECT_FALSE(config.validate(&why));
  EXPECT_NE(why.find("beta_v_z"), std::string::npos) << why;
}

TEST(Compensator, TheConfiguredWaveBandHoldsWithoutACalibrationWindow)
{
  // A bias from a calibration file and the IMU's own orientation: no calibration window, whose end
  // would set up the wave stages again. They must take the configuration from the first sample
  // on: with min_frequency 0.2 Hz a 0.1 Hz heave of 1 m is no wave (nothing below
  // min_frequency is), as it is not after a calibration window.
  CompensatorConfig config = modeConfig(Mode::kDefault);
  config.min_frequency = 0.2;
  const Vector3 bias(0.02, -0.01, 0.03);
  const double rate = 50.0, w = 2.0 * M_PI * 0.1;
  for (bool from_file : { true, false })
  {
    Compensator c(config);
    if (from_file)
    {
      ASSERT_TRUE(c.setConstantBias(bias));
    }
    double wave2 = 0.0, truth2 = 0.0;
    for (int k = 0; k < static_cast<int>(300 * rate); ++k)
    {
      const double t = k / rate;
      const double heave = t < 30.0 && !from_file ? 0.0 : std::sin(w * t);  // still while calibrating
      pbc::ImuSample s;
      s.t = 100.0 + t;
      s.specific_force = Vector3(0.0, 0.0, pbc::kStandardGravity - w * w * heave) + bias;
      s.has_orientation = true;
      CompensatorOutput out;
      c.addSample(s, &out);
      if (t >= 120.0)
      {
        wave2 += out.position_wave.z() * out.position_wave.z();
        truth2 += heave * heave;
      }
    }
    EXPECT_LT(std::sqrt(wave2 / truth2), 0.1) << (from_file ? "bias from a file" : "after a calibration window");
  }
}

// The calibration window's samples are processed a second time once its bias is known (the
// replay); the lever arm's tilt means must still have seen each sample once: what the offset
// takes off the wave outputs is a single pass of LeverArm over the stream's attitudes.
TEST(Compensator, TheLeverArmSeesTheCalibrationWindowOnce)
{
  const Vector3 offset(-5.0, 1.0, 4.0);
  const CompensatorConfig without = modeConfig(Mode::kDefault);
  CompensatorConfig with_arm = without;
  with_arm.lever_arm = offset;
  const double rate = 100.0;
  const auto attitude = [](double t) {
    // A standing heel and trim under the waves' roll and pitch.
    return Eigen::Quaterniond(Eigen::AngleAxisd(0.03 + 0.05 * std::sin(2.0 * M_PI * t / 9.0), Vector3::UnitX()) *
                              Eigen::AngleAxisd(-0.02 + 0.04 * std::sin(2.0 * M_PI * t / 7.0 + 1.0), Vector3::UnitY()));
  };
  // Configured from the start, and set during the window (the replay then goes over the whole
  // window with it, as a single pass from the window's first sample).
  for (const bool set_in_window : { false, true })
  {
    Compensator arm(set_in_window ? without : with_arm), plain(without);
    pbc::LeverArm once(offset);
    int compared = 0;
    for (int k = 0; k < static_cast<int>(60 * rate); ++k)
    {
      const double t = k / rate;
      std::string why;
      if (set_in_window && k == static_cast<int>(5 * rate))
        ASSERT_TRUE(arm.setConfig(with_arm, &why)) << why;
      pbc::ImuSample s;
      s.t = 100.0 + t;
      s.orientation = attitude(t);
      s.has_orientation = true;
      s.specific_force = s.orientation.inverse() * Vector3(0.0, 0.0, pbc::kStandardGravity + 0.3 * std::sin(1.1 * t));
      CompensatorOutput a, b;
      arm.addSample(s, &a);
      plain.addSample(s, &b);
      const pbc::LeverArmOutput expected = once.update(s.orientation, k > 0 ? 1.0 / rate : 0.0);
      ASSERT_EQ(a.state, b.state) << "at " << t << " s";
      if (a.state != pbc::OutputState::kTracking || a.position_wave == Vector3::Zero())
        continue;  // held
      for (int i = 0; i < 3; ++i)
      {
        ASSERT_NEAR(b.position_wave[i] - a.position_wave[i], expected.position[i], 1e-9)
            << "axis " << i << " at " << t << " s" << (set_in_window ? ", set in the window" : "");
        ASSERT_NEAR(b.velocity_wave[i] - a.velocity_wave[i], expected.velocity[i], 1e-9)
            << "axis " << i << " at " << t << " s" << (set_in_window ? ", set in the window" : "");
      }
      ++compared;
    }
    EXPECT_GT(compared, static_cast<int>(40 * rate));
  }
}

// The period searches (the calibration window's, then every fft_hop's) run on the core's design
// thread and are taken up a set time of data later: the outputs are those of the searches made in
// the sample's call, and a reset or recalibration while the window's runs starts a window of its
// own that ends as any other.
TEST(Compensator, PeriodSearchesTakenUpLaterChangeNoOutput)
{
  const CompensatorConfig config = modeConfig(Mode::kDefault);
  const Vector3 bias(0.02, -0.01, 0.03);
  const double rate = 200.0, w = 2.0 * M_PI / 7.0;
  const auto sample = [&](double t) {
    pbc::ImuSample s;
    s.t = 50.0 + t;
    // Heave of 1 m at 7 s: the window (10 s) holds a non-whole number of periods, and the
    // search's harmonic fit decides its offset.
    s.specific_force = Vector3(0.0, 0.0, pbc::kStandardGravity + w * w * std::sin(w * t)) + bias;
    s.has_orientation = true;
    return s;
  };
  Compensator background(config), calling(config);
  calling.setBackgroundDesigns(false);
  bool tracking = false;
  for (int k = 0; k < static_cast<int>(40 * rate); ++k)
  {
    CompensatorOutput a, b;
    background.addSample(sample(k / rate), &a);
    calling.addSample(sample(k / rate), &b);
    ASSERT_EQ(a.state, b.state) << "at " << k / rate << " s";
    ASSERT_EQ(a.position_wave.z(), b.position_wave.z()) << "at " << k / rate << " s";
    ASSERT_EQ(a.position_filtered.z(), b.position_filtered.z()) << "at " << k / rate << " s";
    tracking |= a.state == pbc::OutputState::kTracking;
  }
  EXPECT_TRUE(tracking);

  // Stopped while the search runs (its result, made or not, is dropped), then a window anew:
  // after reset() the outputs are a fresh compensator's on the same samples.
  for (const bool recalibrate : { true, false })
  {
    Compensator c(config), fresh(config);
    int k = 0;
    for (; k < static_cast<int>((config.calibration_duration + 0.05) * rate); ++k)
      c.addSample(sample(k / rate), nullptr);
    EXPECT_FALSE(c.calibrated());
    if (recalibrate)
      c.recalibrate();
    else
      c.reset();
    CompensatorOutput out, expected;
    for (int n = 0; n < static_cast<int>(30 * rate); ++n, ++k)
    {
      c.addSample(sample(k / rate), &out);
      fresh.addSample(sample(k / rate), &expected);
      if (!recalibrate)
      {
        ASSERT_EQ(out.position_wave.z(), expected.position_wave.z()) << "at " << k / rate << " s";
        ASSERT_EQ(out.position_filtered.z(), expected.position_filtered.z()) << "at " << k / rate << " s";
      }
    }
    EXPECT_TRUE(c.calibrated()) << (recalibrate ? "recalibrate" : "reset");
    EXPECT_EQ(out.state, pbc::OutputState::kTracking) << (recalibrate ? "recalibrate" : "reset");
  }
}
