// PaperLoop: the paper's Eq. 2-7 on one axis, on its own.
#include <gtest/gtest.h>

#include <cmath>

#include "periodic_bias_compensation/core/paper_loop.h"

namespace periodic_bias_compensation
{
// Without a period the loop is the paper's plain integration: v_k = v_{k-1} + a dt,
// y_k = y_{k-1} + (v_k - c) dt, and the slow motion is the motion itself.
TEST(PaperLoop, WithoutAPeriodItIntegrates)
{
  PaperLoop loop(100);
  PaperStep in;
  in.acceleration = 0.2;
  in.dt = 0.01;
  in.constant_drift = 0.05;
  double v = 0.0, y = 0.0;
  PaperOutput out;
  for (int k = 0; k < 1000; ++k)
  {
    out = loop.step(in, AxisGains());
    v += 0.2 * 0.01;
    y += (v - 0.05) * 0.01;
  }
  EXPECT_FALSE(out.periodic);
  EXPECT_NEAR(out.position_filtered, y, 1e-12);
  EXPECT_NEAR(out.velocity_filtered, v, 1e-12);
  EXPECT_EQ(out.position_wave, 0.0);
  EXPECT_EQ(out.d_v, 0.0);
}

// A periodic bias of a known period (the paper's bench: 1 Hz sampled at 100 Hz): integrated
// plainly its velocity swings by amplitude / omega and its position walks away; the repetitive
// compensator holds both. A period under kMinPaperPeriod samples is not compensated.
TEST(PaperLoop, HoldsAPeriodicBias)
{
  const double rate = 100.0, f = 1.0, amplitude = 0.05;
  const int period = static_cast<int>(rate / f);
  PaperLoop compensated(2 * period), plain(2 * period);
  PaperStep in;
  in.dt = 1.0 / rate;
  double worst = 0.0, worst_plain = 0.0;
  for (int k = 0; k < static_cast<int>(120 * rate); ++k)
  {
    in.acceleration = amplitude * std::sin(2.0 * M_PI * f * k / rate + 0.7);
    in.period = period;
    const PaperOutput out = compensated.step(in, AxisGains());
    in.period = 0;
    const PaperOutput reference = plain.step(in, AxisGains());
    if (k > 60 * rate)
    {
      worst = std::max(worst, std::abs(out.position_filtered + out.position_wave));
      worst_plain = std::max(worst_plain, std::abs(reference.position_filtered));
    }
  }
  EXPECT_LT(worst, 0.1 * worst_plain);
  PaperLoop short_period(10);
  in.period = kMinPaperPeriod - 1;
  for (int k = 0; k < 20; ++k)
    EXPECT_FALSE(short_period.step(in, AxisGains()).periodic);
}

}  // namespace periodic_bias_compensation
