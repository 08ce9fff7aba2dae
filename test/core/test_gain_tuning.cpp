// tunePaperGains: gains tuned on one shaken run lower paper mode's slow-motion error on runs it
// never saw; the score it reports is the score of the gains it returns; bad input throws.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "../common/test_size.h"
#include "periodic_bias_compensation/core/gain_tuning.h"
#include "synthetic.h"

namespace pbc = periodic_bias_compensation;
using pbc::CompensatorConfig;
using pbc::Vector3;

namespace
{
constexpr double kSettle = 20.0;  // [s]

CompensatorConfig paperConfig()
{
  CompensatorConfig config;
  config.mode = pbc::Mode::kPaper;
  return config;
}

/// A bench shaken on all three axes at rest on average (the paper's setting): true slow motion zero.
/// 120 s (60 s under the sanitizers, where the tuner's 253 runs take minutes).
pbc::test::ShakeRecord shake(unsigned seed, const Vector3& phase)
{
  pbc::test::Shake s;
  s.duration = pbc::test::kSanitized ? 60.0 : 120.0;
  s.amplitude = Vector3(0.05, 0.03, 0.04);
  s.phase = phase;
  s.seed = seed;
  return pbc::test::makeShake(s);
}

/// RMS of paper mode's slow-motion output after kSettle, per axis [m].
Vector3 slowMotionRms(const std::vector<pbc::ImuSample>& samples, const CompensatorConfig& config)
{
  pbc::Compensator compensator(config);
  pbc::CompensatorOutput out;
  Vector3 sum2 = Vector3::Zero();
  int n = 0;
  for (const auto& s : samples)
  {
    compensator.addSample(s, &out);
    if (s.t - samples.front().t >= kSettle)
    {
      sum2 += out.position_filtered.cwiseProduct(out.position_filtered);
      ++n;
    }
  }
  return (sum2 / n).cwiseSqrt();
}
}  // namespace

TEST(GainTuning, TunedGainsHelpOnRunsTheyWereNotTunedOn)
{
  // Tuned on one run, the gains lower the slow-motion error on every axis of three runs with
  // other noise and other phases.
  const auto training = shake(1, Vector3(0.3, 1.1, 2.0));
  const CompensatorConfig start = paperConfig();
  const pbc::GainTuningResult result = pbc::tunePaperGains(training.samples, start, std::nullopt, kSettle);
  CompensatorConfig tuned = start;
  tuned.gains = result.gains;
  for (int i = 0; i < 3; ++i)
    std::printf("[gain tuning] axis %d: training %.5f -> %.5f m (alpha_v %.2f beta_v %.1f alpha_p %.2f beta_p %.1f)\n",
                i, result.score_start[i], result.score[i], result.gains[i].alpha_v, result.gains[i].beta_v,
                result.gains[i].alpha_p, result.gains[i].beta_p);
  const Vector3 phases[] = { Vector3(2.5, 0.2, 4.0), Vector3(1.2, 3.3, 0.7), Vector3(5.1, 2.0, 2.9) };
  for (unsigned run = 0; run < 3; ++run)
  {
    const auto held_out = shake(2 + run, phases[run]);
    const Vector3 before = slowMotionRms(held_out.samples, start);
    const Vector3 after = slowMotionRms(held_out.samples, tuned);
    for (int i = 0; i < 3; ++i)
    {
      std::printf("[gain tuning] held-out run %u, axis %d: %.5f -> %.5f m (%.2f)\n", run, i, before[i], after[i],
                  after[i] / before[i]);
      EXPECT_LT(after[i], before[i]) << "held-out run " << run << ", axis " << i;
    }
  }
  EXPECT_EQ(result.runs, 1 + 2 * 2 * 7 * 9);
}

TEST(GainTuning, ReportedScoreIsTheScoreOfTheReturnedGains)
{
  const auto training = shake(3, Vector3(1.0, 2.0, 3.0));
  CompensatorConfig start = paperConfig();
  const pbc::GainTuningResult result = pbc::tunePaperGains(training.samples, start, std::nullopt, kSettle);
  start.gains = result.gains;
  const Vector3 rerun = slowMotionRms(training.samples, start);
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_NEAR(rerun[i], result.score[i], 1e-12 + 1e-9 * result.score[i]) << "axis " << i;
    EXPECT_LE(result.score[i], result.score_start[i]) << "axis " << i;
  }
}

TEST(GainTuning, BadInputThrows)
{
  const auto training = shake(1, Vector3(0.3, 1.1, 2.0));
  EXPECT_THROW(pbc::tunePaperGains({}, paperConfig(), std::nullopt, kSettle), std::invalid_argument);
  EXPECT_THROW(pbc::tunePaperGains(training.samples, CompensatorConfig(), std::nullopt, kSettle),
               std::invalid_argument);  // default mode has no alpha/beta loop
  pbc::GainGrid unstable;
  unstable.alpha = { 2.5 };  // outside 0 <= alpha < 2
  try
  {
    pbc::tunePaperGains(training.samples, paperConfig(), std::nullopt, kSettle, unstable);
    ADD_FAILURE() << "an alpha of 2.5 was tried";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("alpha"), std::string::npos) << e.what();
  }
}

TEST(GainTuning, YamlHasEveryGainKey)
{
  std::array<pbc::AxisGains, 3> gains;
  gains[2].beta_p = 7.5;
  const std::string yaml = pbc::gainsToYaml(gains, "test");
  EXPECT_EQ(yaml.rfind("# test\n", 0), 0u);
  for (const char* key : { "alpha_v_", "alpha_p_", "beta_v_", "beta_p_" })
    for (const char* axis : { "x", "y", "z" })
      EXPECT_NE(yaml.find(std::string(key) + axis + ": "), std::string::npos) << key << axis;
  EXPECT_NE(yaml.find("beta_p_z: 7.5\n"), std::string::npos) << yaml;
}
