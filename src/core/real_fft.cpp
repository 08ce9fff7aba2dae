#include "real_fft.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "periodic_bias_compensation/common/fftw_planner.h"

namespace periodic_bias_compensation
{
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

void lowerThreadPriority()
{
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
}

void warmFftPlans(const std::vector<int>& sizes)
{
  for (int n : sizes)
    RealFft planned(n);
}

RealFft::RealFft(int n) : n_(n)
{
  in = fftw_alloc_real(n);
  out = fftw_alloc_complex(n / 2 + 1);
  std::lock_guard<std::mutex> lock(fftwPlannerMutex());
  plan_ = fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
  inverse_plan_ = fftw_plan_dft_c2r_1d(n, out, in, FFTW_ESTIMATE);
}

RealFft::~RealFft()
{
  std::lock_guard<std::mutex> lock(fftwPlannerMutex());
  fftw_destroy_plan(plan_);
  fftw_destroy_plan(inverse_plan_);
  fftw_free(in);
  fftw_free(out);
}

}  // namespace periodic_bias_compensation
