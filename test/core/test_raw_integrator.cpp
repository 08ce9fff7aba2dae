// RawIntegrator: trapezoidal double integration, exact for a constant acceleration; no
// integration across a restart; reset to zero.
#include <gtest/gtest.h>

#include "periodic_bias_compensation/core/raw_integrator.h"

using periodic_bias_compensation::RawIntegrator;
using periodic_bias_compensation::Vector3;

TEST(RawIntegrator, ConstantAccelerationAndRestarts)
{
  RawIntegrator raw;
  const Vector3 a(0.2, 0.0, 0.0);
  for (int i = 0; i <= 100; ++i)
  {
    raw.add(0.01 * i, a, false);
  }
  EXPECT_NEAR(raw.position().x(), 0.5 * 0.2 * 1.0 * 1.0, 1e-9);
  const double before_gap = raw.position().x();
  raw.add(5.0, a, true);  // after a gap: no integration across it
  EXPECT_DOUBLE_EQ(raw.position().x(), before_gap);
  raw.reset();
  EXPECT_DOUBLE_EQ(raw.position().norm(), 0.0);
}
