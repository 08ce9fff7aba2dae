// Fuzz target: the simulator's scenario YAML loader (sim::parseScenario) on arbitrary text.
// Allowed outcomes: a scenario, or std::runtime_error (YAML::Exception derives from it) with a
// message. Anything else (another exception type, a crash, UB, a hang) is a finding.
// A scenario that parses is also simulated for a few samples (every value finite).
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.h"
#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/sim/simulator.h"

namespace sim = periodic_bias_compensation::sim;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string text(reinterpret_cast<const char*>(data), size);
  sim::Scenario scenario;
  try
  {
    scenario = sim::parseScenario(text, "fuzz.yaml");
  }
  catch (const std::runtime_error& e)
  {
    if (std::string(e.what()).empty())
    {
      pbc_fuzz::fail("parseScenario threw without a message");
    }
    return 0;
  }
  // Round trip: what toYaml writes must parse again.
  try
  {
    sim::parseScenario(sim::toYaml(scenario), "round-trip");
  }
  catch (const std::runtime_error& e)
  {
    pbc_fuzz::fail(std::string("toYaml output of a valid scenario does not parse: ") + e.what());
  }
  try
  {
    sim::Simulator simulator(scenario, scenario.seed);
    sim::Sample sample;
    for (int k = 0; k < 20 && simulator.next(&sample); ++k)
    {
      if (!sample.accel.allFinite() || !sample.gyro.allFinite() || !std::isfinite(sample.stamp) ||
          !sample.orientation.coeffs().allFinite())
      {
        pbc_fuzz::fail("a validated scenario simulates a non-finite sample at k = " + std::to_string(k));
      }
    }
  }
  catch (const std::runtime_error&)
  {
    // The Simulator validates again; refusing here is allowed.
  }
  return 0;
}
