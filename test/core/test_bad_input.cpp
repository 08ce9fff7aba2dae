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
void feed(Compensator& c, const pbc::test::ShakeRecord& r, std::size_t first, std::size_t count, double time_shift = 0.0)
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

TEST(BadInput, ZeroAndNonUnitQuaternionsAreRejected)
{
  const auto r = record();
  Compensator c;
  feed(c, r, 0, 100);
  pbc::ImuSample s = r.samples[100];
  s.orientation = pbc::Quaternion(0, 0, 0, 0);
  EXPECT_EQ(c.addSample(s, nullptr), SampleStatus::kRejectedBadQuaternion);
  s.orientation = pbc::Quaternion(1.2, 0, 0, 0);
  EXPECT_EQ(c.addSample(s, nullptr), SampleStatus::kRejectedBadQuaternion);
  // Slightly off unit (float rounding in a driver) is normalised and accepted.
  s.orientation = pbc::Quaternion(1.0 + 1e-4, 0, 0, 0);
  EXPECT_EQ(c.addSample(s, nullptr), SampleStatus::kAccepted);
  EXPECT_EQ(c.counters().rejected_bad_quaternion, 2u);
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
  // A bag replayed with --loop: the second pass must give what a fresh compensator gives, with
  // and without orientation in the messages (then the level is measured again too).
  for (bool with_orientation : { true, false })
  {
    pbc::test::Shake shake;
    shake.duration = 40.0;
    shake.with_orientation = with_orientation;
    const auto r = pbc::test::makeShake(shake);
    Compensator looped, fresh;
    feed(looped, r, 0, r.samples.size());
    CompensatorOutput out_looped, out_fresh;
    EXPECT_EQ(looped.addSample(r.samples[0], &out_looped), SampleStatus::kResetBackwards);
    EXPECT_EQ(looped.counters().resets_backwards, 1u);
    fresh.addSample(r.samples[0], &out_fresh);
    for (std::size_t k = 1; k < r.samples.size(); ++k)
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
  pbc::ImuSample late = r.samples[2000];
  late.t += 5.0;  // 5 s of missing samples, far over max_gap
  EXPECT_EQ(c.addSample(late, &out), SampleStatus::kGapReset);
  EXPECT_EQ(c.counters().gap_resets, 1u);
  EXPECT_TRUE(c.calibrated());
  EXPECT_NEAR((c.constantBias() - bias).norm(), 0.0, 1e-9);
  EXPECT_NEAR(out.position_filtered.norm(), 0.0, 1e-6) << "integration restarts from the gap";
  feed(c, r, 2001, 500, 5.0);
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
  // from the calibration window's mean specific force and the wave is still tracked.
  pbc::test::Shake shake;
  shake.with_orientation = false;
  auto r = pbc::test::makeShake(shake);
  const pbc::Quaternion tilt(Eigen::AngleAxisd(3.0 * M_PI / 180.0, Vector3::UnitX()));
  for (auto& s : r.samples)
    s.specific_force = tilt.inverse() * s.specific_force;
  Compensator c;
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
