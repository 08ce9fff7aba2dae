#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "periodic_bias_compensation/sim/effects.h"
#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/sim/simulator.h"

namespace sim = periodic_bias_compensation::sim;

namespace
{
// Expects parseScenario to throw with a message containing `needle`.
void expectError(const std::string& yaml, const std::string& needle)
{
  try
  {
    sim::parseScenario(yaml, "test.yaml");
    FAIL() << "no error for:\n" << yaml;
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(Scenario, DefaultsWhenEmpty)
{
  const sim::Scenario s = sim::parseScenario("{}");
  EXPECT_DOUBLE_EQ(s.rate, 100.0);
  EXPECT_DOUBLE_EQ(s.duration, 60.0);
  EXPECT_DOUBLE_EQ(s.start_time, 1000.0);
  EXPECT_EQ(s.motion.type, sim::MotionType::kStatic);
  EXPECT_FALSE(s.temperature.enabled);
  EXPECT_EQ(sim::sampleCount(s), 6000);
}

TEST(Scenario, ParsesSinusoidsAndEffects)
{
  const sim::Scenario s = sim::parseScenario(R"(
rate: 50
motion:
  type: sinusoids
  sinusoids:
    surge: {amplitude: 0.05, frequency: 0.443, phase: 0.1}
    roll: {amplitude: 0.1, frequency: 0.1}
effects:
  - name: constant_bias
    accel: 0.02
  - name: white_noise
    enabled: false
    accel_density: [0.001, 0.002, 0.003]
)");
  EXPECT_EQ(s.motion.type, sim::MotionType::kSinusoids);
  EXPECT_DOUBLE_EQ(s.motion.sinusoids[sim::kSurge].amplitude, 0.05);
  EXPECT_DOUBLE_EQ(s.motion.sinusoids[sim::kSurge].phase, 0.1);
  EXPECT_DOUBLE_EQ(s.motion.sinusoids[sim::kRoll].frequency, 0.1);
  ASSERT_EQ(s.effects.size(), 2u);
  EXPECT_FALSE(s.effects[1].enabled);
  const sim::EffectSpec bias = sim::completeEffect(s.effects[0]);
  EXPECT_EQ(bias.params.at("accel").size(), 3u);
  EXPECT_DOUBLE_EQ(bias.params.at("accel")[2], 0.02);
  EXPECT_DOUBLE_EQ(bias.params.at("gyro")[0], 0.0);
}

TEST(Scenario, RejectsUnknownKeysNamingThem)
{
  expectError("rat: 100", "'rat'");
  expectError("motion: {type: sinusoids, sinusoids: {surge: {amplitud: 1}}}", "motion.sinusoids.surge.amplitud");
  expectError("motion: {type: static, sea: {}}", "motion.sea");
  expectError("effects: [{name: white_noise, accel_dens: 1}]", "effects[0].accel_dens");
  expectError("effects: [{name: no_such_effect}]", "no_such_effect");
  expectError("temperature: {mean: 20, periode: 3}", "temperature.periode");
}

TEST(Scenario, RejectsOutOfRangeValuesNamingThem)
{
  expectError("rate: -1", "'rate'");
  expectError("duration: 0", "'duration'");
  expectError("start_time: 0", "'start_time'");
  expectError("motion: {type: sinusoids, sinusoids: {surge: {amplitude: 1, frequency: 60}}}",
              "motion.sinusoids.surge.frequency");
  expectError("effects: [{name: white_noise, accel_density: -1}]", "effects[0].accel_density");
  expectError("effects: [{name: constant_bias, accel: [1, 2]}]", "effects[0].accel");
  expectError("effects: [{name: thermal_drift, accel_coefficient: 0.001}]", "thermal_drift");
  expectError("motion: {type: sea}", "motion.sea.systems");
  expectError("motion: {type: route}", "motion.route.legs");
  expectError("motion: {type: wobble}", "motion.type");
  expectError("rate: abc", "'rate'");
}

TEST(Scenario, ValidatesScenarioBuiltInCode)
{
  sim::Scenario s;
  s.effects.push_back(sim::defaultEffect("white_noise"));
  s.effects.back().params["accel_density"] = { 0.0, 0.0, -1.0 };
  EXPECT_THROW(sim::validateScenario(s), std::runtime_error);
  s.effects.back().params["accel_density"] = { 0.0, 0.0, 1.0 };
  EXPECT_NO_THROW(sim::validateScenario(s));
}

TEST(Scenario, EffectsCanBeFoundAndSwitched)
{
  sim::Scenario s;
  s.effects.push_back(sim::defaultEffect("constant_bias"));
  s.effects.push_back(sim::defaultEffect("white_noise"));
  ASSERT_NE(sim::findEffect(s, "white_noise"), nullptr);
  EXPECT_EQ(sim::findEffect(s, "vibration"), nullptr);
  EXPECT_TRUE(sim::setEffectEnabled(s, "white_noise", false));
  EXPECT_FALSE(sim::findEffect(s, "white_noise")->enabled);
  EXPECT_FALSE(sim::setEffectEnabled(s, "vibration", true));
}

TEST(Scenario, VocabularyHasEveryEffectWithUnits)
{
  const std::vector<std::string> names = { "white_noise",     "constant_bias", "bias_random_walk", "bias_instability",
                                           "periodic_bias",   "thermal_drift", "scale_factor",     "misalignment",
                                           "gravity_leakage", "lever_arm",     "vibration",        "quantization",
                                           "saturation",      "sample_hold",   "timestamp_jitter", "dropouts" };
  EXPECT_EQ(sim::effectVocabulary().size(), names.size());
  for (const std::string& n : names)
  {
    const sim::EffectInfo& info = sim::effectInfo(n);
    EXPECT_FALSE(info.params.empty()) << n;
    for (const sim::ParamInfo& p : info.params)
    {
      EXPECT_FALSE(p.unit.empty()) << n << "." << p.name;
    }
  }
}

TEST(Scenario, YamlRoundTripGivesTheSameSamples)
{
  for (const char* file : { "paper_bench", "underway_course_changes", "thermal_day_night", "swell_and_wind_sea" })
  {
    SCOPED_TRACE(file);
    sim::Scenario a = sim::loadScenario(std::string(PBC_SCENARIO_DIR) + "/" + file + ".yaml");
    a.duration = 3.0;
    a.effects.push_back(sim::defaultEffect("vibration"));
    a.effects.back().params["frequency"] = { 1.0 / 3.0 };
    a.effects.back().params["accel_amplitude"] = { 0.1, 0.2, 0.3 };
    a.effects.back().enabled = false;
    const std::string yaml = sim::toYaml(a);
    const sim::Scenario b = sim::parseScenario(yaml, "round trip");
    EXPECT_EQ(sim::toYaml(b), yaml);
    EXPECT_FALSE(b.effects.back().enabled);
    sim::Simulator sa(a, 11);
    sim::Simulator sb(b, 11);
    sim::Sample x;
    sim::Sample y;
    while (sa.next(&x))
    {
      ASSERT_TRUE(sb.next(&y));
      ASSERT_EQ(x.accel, y.accel);
      ASSERT_EQ(x.gyro, y.gyro);
      ASSERT_EQ(x.truth.position, y.truth.position);
    }
    EXPECT_FALSE(sb.next(&y));
  }
}

TEST(Scenario, YamlRoundTripOfDefaultsAndSpecialText)
{
  sim::Scenario a;
  a.description = "quotes \" and: colons, # hashes";
  a.temperature.enabled = true;
  const sim::Scenario b = sim::parseScenario(sim::toYaml(a), "round trip");
  EXPECT_EQ(b.name, "");
  EXPECT_EQ(b.description, a.description);
  EXPECT_TRUE(b.temperature.enabled);
  EXPECT_EQ(sim::toYaml(b), sim::toYaml(a));
}

TEST(Scenario, FactoryBuildsEveryVocabularyEffect)
{
  for (const sim::EffectInfo& info : sim::effectVocabulary())
  {
    EXPECT_NE(sim::makeEffect(sim::defaultEffect(info.name), 1, 100.0), nullptr) << info.name;
  }
  EXPECT_THROW(sim::makeEffect(sim::EffectSpec{ "no_such_effect", true, {} }, 1, 100.0), std::runtime_error);
}
