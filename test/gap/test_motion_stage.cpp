// The diagnosis's motion stage: the sea state and the standing tilt of a recording against the
// scenario's, fitted before any sensor effect.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../common/test_size.h"
#include "periodic_bias_compensation/gap/gap.h"

namespace gap = periodic_bias_compensation::gap;
namespace sim = periodic_bias_compensation::sim;

namespace
{
/// A moored ship in a long-crested JONSWAP sea whose heave is the wave elevation (response 1,
/// no length filter), 10 Hz, 20 min, with a little sensor noise.
sim::Scenario mooredSea(double significant_height, double peak_period)
{
  sim::Scenario s;
  s.name = "moored_sea";
  s.rate = 10.0;
  s.duration = 1200.0;
  s.motion.type = sim::MotionType::kSea;
  s.motion.sea.response = { { 0.5, 0.5, 1.0, 0.8, 0.6, 0.1 } };
  s.motion.sea.length = 0.0;
  sim::WaveSystem waves;
  waves.significant_height = significant_height;
  waves.peak_period = peak_period;
  s.motion.sea.systems = { waves };
  sim::EffectSpec noise{ "white_noise", true, {} };
  noise.params["accel_density"] = { 1e-3 };
  noise.params["gyro_density"] = { 1e-4 };
  s.effects = { noise };
  return s;
}
}  // namespace

TEST(GapMotion, SeaStateOfASimulatedSea)
{
  const gap::MotionSummary m = gap::summariseMotion(gap::simulateRecording(mooredSea(2.0, 9.0), 11));
  EXPECT_NEAR(m.wave_height, 2.0, 0.2);
  EXPECT_NEAR(m.peak_period, 9.0, 0.9);
  EXPECT_NEAR(m.roll, 0.0, 0.01);
  EXPECT_NEAR(m.pitch, 0.0, 0.01);
}

TEST(GapMotion, AnotherSeaAndATrimAreFittedBeforeSensorEffects)
{
  // The recording: a higher, longer sea and a 2 degree trim by the stern; the scenario: a small
  // short sea on an even keel.
  sim::Scenario recorded = mooredSea(2.0, 9.0);
  recorded.motion.pitch = 0.035;
  gap::DiagnoseOptions opt;
  opt.ensemble = periodic_bias_compensation::test::ensembleToRun(opt.ensemble);
  const gap::Report rep = gap::diagnose(gap::simulateRecording(recorded, 12), mooredSea(1.0, 6.0), opt);
  const gap::MotionFit& m = rep.motion;
  ASSERT_TRUE(m.differs) << gap::reportSummary(rep);
  EXPECT_LT(m.gap_after, m.gap_before) << gap::reportSummary(rep);
  if (periodic_bias_compensation::test::kSanitized)
  {
    return;  // the accuracy below needs the full ensemble: asserted by the normal build
  }
  EXPECT_NEAR(m.real.wave_height, 2.0, 0.2);
  EXPECT_NEAR(m.scenario.wave_height, 1.0, 0.1);
  EXPECT_NEAR(m.real.pitch - m.scenario.pitch, 0.035, 0.005);
  ASSERT_EQ(m.findings.size(), 2u) << gap::reportSummary(rep);
  EXPECT_NE(m.findings[0].find("standing tilt"), std::string::npos) << m.findings[0];
  EXPECT_NE(m.findings[1].find("sea state"), std::string::npos) << m.findings[1];
  EXPECT_EQ(m.adopted, "tilt, heading and sea state") << gap::reportSummary(rep);
  EXPECT_LT(m.gap_after, 0.5 * m.gap_before) << gap::reportSummary(rep);
  EXPECT_NEAR(m.fitted.motion.sea.systems.at(0).significant_height, 2.0, 0.25);
  EXPECT_NEAR(m.fitted.motion.sea.systems.at(0).peak_period, 9.0, 0.9);
  // The trim is motion, not a sensor bias.
  EXPECT_NE(rep.verdict_effect, "constant_bias") << gap::reportSummary(rep);
  EXPECT_EQ(gap::reportJson(rep).at("motion").at("differs"), true);
}

TEST(GapMotion, TheScenariosOwnMotionDoesNotDiffer)
{
  const sim::Scenario s = mooredSea(1.5, 8.0);
  gap::DiagnoseOptions opt;
  opt.ensemble = periodic_bias_compensation::test::ensembleToRun(opt.ensemble);
  const gap::Report rep = gap::diagnose(gap::simulateRecording(s, 13), s, opt);
  EXPECT_FALSE(rep.motion.differs) << gap::reportSummary(rep);
  EXPECT_TRUE(rep.motion.adopted.empty());
  EXPECT_EQ(rep.motion.gap_before, rep.motion.gap_after);
}

TEST(GapMotion, AHullsOwnResponsesAreFittedBeforeSensorEffects)
{
  // The recording: the scenario's sea on the bow quarter and a trim, but a hull that rolls three
  // times as much and whose surge, sway, roll, pitch and yaw keep no phase with the waves.
  sim::Scenario scenario = mooredSea(1.5, 8.0);
  scenario.motion.sea.systems[0].direction = 0.8;
  sim::Scenario recorded = scenario;
  recorded.motion.pitch = 0.02;
  recorded.motion.sea.response[sim::kRoll] *= 3.0;
  recorded.motion.sea.response_coherence = 0.0;
  gap::DiagnoseOptions opt;
  opt.ensemble = periodic_bias_compensation::test::ensembleToRun(opt.ensemble);
  const gap::Report rep = gap::diagnose(gap::simulateRecording(recorded, 14), scenario, opt);
  const gap::MotionFit& m = rep.motion;
  ASSERT_TRUE(m.differs) << gap::reportSummary(rep);
  EXPECT_LT(m.gap_after, m.gap_before) << gap::reportSummary(rep);
  if (periodic_bias_compensation::test::kSanitized)
  {
    return;  // the accuracy below needs the full ensemble: asserted by the normal build
  }
  EXPECT_NE(m.adopted.find("wave responses"), std::string::npos) << gap::reportSummary(rep);
  EXPECT_NE(m.adopted.find("response coherence"), std::string::npos) << gap::reportSummary(rep);
  EXPECT_LT(m.gap_after, 0.3 * m.gap_before) << gap::reportSummary(rep);
  EXPECT_NEAR(m.fitted.motion.sea.response[sim::kRoll], 2.4, 0.6) << gap::reportSummary(rep);
  EXPECT_LT(m.fitted.motion.sea.response_coherence, 1.0);
  // No sensor effect is made of the motion.
  EXPECT_LT(rep.confidence, 0.5) << gap::reportSummary(rep);
}

TEST(GapMotion, AHullThatDoesNotFollowShortWavesIsFittedItsLength)
{
  // The recording: a 4 s wind sea under a 12 m hull, whose short waves move it less; the scenario:
  // the same sea on a hull that follows the water at a point.
  sim::Scenario scenario = mooredSea(1.5, 4.0);
  sim::Scenario recorded = scenario;
  recorded.motion.sea.length = 12.0;
  const gap::MotionSummary real = gap::summariseMotion(gap::simulateRecording(recorded, 15));
  const auto runs = [](const sim::Scenario& s) {
    std::vector<gap::MotionSummary> out;
    for (int i = 0; i < periodic_bias_compensation::test::ensembleToRun(4); ++i)
      out.push_back(gap::summariseMotion(gap::simulateRecording(s, 100 + i)));
    return out;
  };
  std::vector<std::string> findings;
  const auto fit = gap::fitShortWaves(real, scenario, runs(scenario), &findings);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->scenario.motion.sea.length, 12.0, 2.4);
  ASSERT_EQ(findings.size(), 1u);
  EXPECT_NE(findings[0].find("hull of length"), std::string::npos) << findings[0];
  // The scenario's own hull: nothing to fit.
  findings.clear();
  EXPECT_FALSE(gap::fitShortWaves(real, recorded, runs(recorded), &findings).has_value()) << findings.front();
}

namespace
{
/// A "recording" whose motion no sea of the scenario's kind makes: a buoy on a bench rig, heave,
/// roll and pitch as pure lines at their own periods, with the scenario's sensor; and, when
/// `noisy`, an accelerometer five times as noisy.
gap::Recording rigRecording(bool noisy, std::uint64_t seed)
{
  sim::Scenario rig = mooredSea(1.5, 8.0);
  rig.motion.type = sim::MotionType::kSinusoids;
  rig.motion.sinusoids[sim::kHeave] = { 0.6, 1.0 / 9.0, 0.0 };
  rig.motion.sinusoids[sim::kRoll] = { 0.08, 1.0 / 5.0, 0.3 };
  rig.motion.sinusoids[sim::kPitch] = { 0.05, 1.0 / 13.0, 1.1 };
  if (noisy)
    rig.effects[0].params["accel_density"] = { 5e-3 };
  return gap::simulateRecording(rig, seed);
}
}  // namespace

TEST(GapMotion, AMotionTheScenarioCannotTakeIsLeftOutAndTheNoiseStillNamed)
{
  // Without leaving the motion's departures out, the lines' spectra (gap about 1) bury the noise,
  // which no candidate then explains enough of to be named.
  const sim::Scenario scenario = mooredSea(1.5, 8.0);
  gap::DiagnoseOptions opt;
  opt.ensemble = periodic_bias_compensation::test::ensembleToRun(opt.ensemble);
  const gap::Report noisy = gap::diagnose(rigRecording(true, 21), scenario, opt);
  ASSERT_TRUE(noisy.motion.differs) << gap::reportSummary(noisy);
  EXPECT_EQ(gap::reportJson(noisy).at("motion").at("left_out").size(), noisy.motion.left_out.size());
  if (periodic_bias_compensation::test::kSanitized)
  {
    // Three runs leave two to judge each against: the null gap is too wide to call the motion
    // unexplained. The rest needs the full ensemble: asserted by the normal build.
    return;
  }
  EXPECT_TRUE(noisy.motion.unexplained) << gap::reportSummary(noisy);
  EXPECT_FALSE(noisy.motion.left_out.empty()) << gap::reportSummary(noisy);
  EXPECT_LT(noisy.gap_before, noisy.motion.gap_after) << gap::reportSummary(noisy);
  EXPECT_EQ(noisy.verdict_effect, "white_noise") << gap::reportSummary(noisy);
  // The same rig with the scenario's own sensor: the motion is left out, and no sensor effect is
  // confidently made of what remains.
  const gap::Report plain = gap::diagnose(rigRecording(false, 21), scenario, opt);
  EXPECT_TRUE(plain.motion.unexplained) << gap::reportSummary(plain);
  EXPECT_LT(plain.confidence, 0.5) << gap::reportSummary(plain);
}

TEST(GapSimulate, VariantsOnOneMotionAreTheRecordingsSimulatedAlone)
{
  // Sensors that read the motion's angular acceleration (a lever arm), lose samples and jitter
  // their stamps, and one that cannot be simulated, on one evaluation of a moored sea's motion.
  const sim::Scenario sea = mooredSea(1.5, 8.0);
  std::vector<sim::Scenario> variants(4, sea);
  variants[1].effects.push_back({ "lever_arm", true, { { "offset", { 2.0, -1.0, 3.0 } } } });
  variants[2].effects.push_back({ "dropouts", true, { { "probability", { 0.01 } }, { "burst_length", { 3.0 } } } });
  variants[2].effects.push_back({ "timestamp_jitter", true, { { "sigma", { 2e-3 } } } });
  variants[3].effects.push_back({ "scale_factor", true, { { "accel", { 0.9, 0.0, 0.0 } } } });  // beyond +-0.5
  std::vector<int> made;
  const std::vector<std::string> errors = gap::simulateVariants(variants, 21, [&](int v, gap::Recording& r) {
    made.push_back(v);
    const gap::Recording alone = gap::simulateRecording(variants[v], 21);
    ASSERT_EQ(r.size(), alone.size()) << "variant " << v;
    EXPECT_EQ(r.stamp, alone.stamp) << "variant " << v;
    EXPECT_TRUE(r.data == alone.data) << "variant " << v;
    for (std::size_t k = 0; k < r.size(); ++k)
    {
      ASSERT_TRUE(r.orientation[k].coeffs() == alone.orientation[k].coeffs()) << "variant " << v << " sample " << k;
    }
  });
  EXPECT_EQ(made, (std::vector<int>{ 0, 1, 2 }));
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_EQ(errors[0] + errors[1] + errors[2], "");
  EXPECT_NE(errors[3].find("0.9 outside [-0.5, 0.5]"), std::string::npos) << errors[3];
  // The lever arm moves the recording: the variants are not the same sensor.
  gap::Recording plain = gap::simulateRecording(variants[0], 21);
  gap::Recording lever = gap::simulateRecording(variants[1], 21);
  EXPECT_GT((plain.data - lever.data).cwiseAbs().maxCoeff(), 1e-3);
}
