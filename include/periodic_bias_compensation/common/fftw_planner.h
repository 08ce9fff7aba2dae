// The one lock around FFTW's planner for every library of the package.
#pragma once

#include <mutex>

namespace periodic_bias_compensation
{
/// FFTW executes existing plans from any thread, but its planner (creating and destroying plans)
/// is global and not thread-safe: the core's transforms and the gap diagnosis's Welch spectra
/// plan under this one mutex, so compensators and spectra may run in threads side by side.
inline std::mutex& fftwPlannerMutex()
{
  static std::mutex mutex;
  return mutex;
}
}  // namespace periodic_bias_compensation
