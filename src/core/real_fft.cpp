#include "real_fft.h"

#include <cmath>
#include <unordered_map>

#include "periodic_bias_compensation/common/fftw_planner.h"

namespace periodic_bias_compensation
{
std::vector<double> hannWindow(int n, double* power)
{
  std::vector<double> window(n);
  double sum = 0.0;
  for (int i = 0; i < n; ++i)
  {
    window[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * i / n);
    sum += window[i] * window[i];
  }
  if (power)
    *power = sum;
  return window;
}

int fastFftSize(int n)
{
  for (int m = n;; ++m)
  {
    int r = m;
    for (int f : { 2, 3, 5 })
      while (r % f == 0)
        r /= f;
    if (r == 1)
      return m;
  }
}

namespace
{
/// The plans of one size, made once per process and shared by every RealFft of that size: FFTW
/// executes a plan on other arrays of the same alignment from any thread (new-array execute).
struct Plans
{
  fftw_plan forward;
  fftw_plan inverse;
};

Plans plansOfSize(int n)
{
  // Never destroyed: the background threads may still plan while the process exits.
  static std::mutex& cache_mutex = *new std::mutex;
  static std::unordered_map<int, Plans>& cache = *new std::unordered_map<int, Plans>;
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    const auto found = cache.find(n);
    if (found != cache.end())
      return found->second;
  }
  // Planned under the planner's lock, with arrays of its own (fftw_alloc's alignment, as every
  // RealFft's), which the plans do not need afterwards.
  std::lock_guard<std::mutex> planner(fftwPlannerMutex());
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    const auto found = cache.find(n);
    if (found != cache.end())
      return found->second;  // planned by another thread meanwhile
  }
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  const Plans plans{ fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE), fftw_plan_dft_c2r_1d(n, out, in, FFTW_ESTIMATE) };
  fftw_free(in);
  fftw_free(out);
  std::lock_guard<std::mutex> lock(cache_mutex);
  cache.emplace(n, plans);
  return plans;
}
}  // namespace

void warmFftPlans(const std::vector<int>& sizes)
{
  for (int n : sizes)
    plansOfSize(n);
}

RealFft::RealFft(int n) : n_(n)
{
  const Plans plans = plansOfSize(n);
  plan_ = plans.forward;
  inverse_plan_ = plans.inverse;
  in = fftw_alloc_real(n);
  out = fftw_alloc_complex(n / 2 + 1);
}

RealFft::~RealFft()
{
  fftw_free(in);
  fftw_free(out);
}

}  // namespace periodic_bias_compensation
