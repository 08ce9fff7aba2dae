// How much work a test sized for accuracy does in this build.
//
// The sanitizer build (PBC_SANITIZED) runs every test about ten times slower. There, a test that
// repeats one computation over several seeds for an accuracy figure runs its first seed only:
// the sanitizers look for memory errors and undefined behaviour, and one seed takes the same
// code paths as the rest. The accuracy over every seed is asserted by the normal build.
#pragma once

namespace periodic_bias_compensation
{
namespace test
{
#ifdef PBC_SANITIZED
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

/// How many of a test's `seeds` seeds this build runs.
constexpr unsigned seedsToRun(unsigned seeds)
{
  return kSanitized ? 1u : seeds;
}

/// How many simulated runs a diagnosis sized for accuracy uses in this build (the gap
/// diagnosis's ensemble): under the sanitizers 3, enough for every code path; its accuracy is
/// then asserted by the normal build only.
constexpr int ensembleToRun(int ensemble)
{
  return kSanitized ? 3 : ensemble;
}
}  // namespace test
}  // namespace periodic_bias_compensation
