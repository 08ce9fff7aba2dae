// Every shipped scenario loads and simulates a few seconds with finite output.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "periodic_bias_compensation/sim/simulator.h"

namespace sim = periodic_bias_compensation::sim;

namespace
{
std::vector<std::string> shippedScenarios()
{
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::directory_iterator(PBC_SCENARIO_DIR))
  {
    if (entry.path().extension() == ".yaml")
    {
      out.push_back(entry.path().string());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool finite(const sim::Vector3& v)
{
  return v.allFinite();
}
}  // namespace

TEST(ShippedScenarios, TheDocumentedOnesExist)
{
  const std::vector<std::string> files = shippedScenarios();
  for (const char* name : { "paper_bench", "paper_static", "moored_sea_state_4", "underway_course_changes",
                            "thermal_day_night", "swell_and_wind_sea" })
  {
    const std::string file = std::string(PBC_SCENARIO_DIR) + "/" + name + ".yaml";
    EXPECT_NE(std::find(files.begin(), files.end(), file), files.end()) << file;
  }
}

TEST(ShippedScenarios, EachLoadsAndSimulatesFiniteSamples)
{
  for (const std::string& file : shippedScenarios())
  {
    SCOPED_TRACE(file);
    sim::Scenario s;
    ASSERT_NO_THROW(s = sim::loadScenario(file));
    EXPECT_FALSE(s.name.empty());
    EXPECT_GT(s.start_time, 0.0);
    s.duration = std::min(s.duration, 5.0);
    sim::Simulator simulator(s, s.seed);
    sim::Sample smp;
    std::int64_t n = 0;
    double previous = -1.0;
    while (simulator.next(&smp))
    {
      ++n;
      ASSERT_TRUE(finite(smp.accel) && finite(smp.gyro) && smp.orientation.coeffs().allFinite());
      ASSERT_TRUE(finite(smp.truth.position) && finite(smp.truth.velocity) && finite(smp.truth.acceleration));
      ASSERT_NEAR(smp.orientation.norm(), 1.0, 1e-9);
      ASSERT_TRUE(std::isfinite(smp.stamp));
      ASSERT_GT(smp.t, previous);
      previous = smp.t;
      // Specific force stays within a few g for every shipped scenario.
      ASSERT_LT(smp.accel.norm(), 40.0);
    }
    EXPECT_EQ(n, sim::sampleCount(s));
    EXPECT_GT(n, 4);
  }
}
