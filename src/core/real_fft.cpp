#include "real_fft.h"

#include <cmath>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <condition_variable>
#include <deque>
#include <thread>

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
/// The thread behind planInBackground: a queue of tasks, run one at a time.
class BackgroundPlanner
{
public:
  BackgroundPlanner() : thread_([this] { run(); })
  {
  }
  ~BackgroundPlanner()
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    thread_.join();
  }
  void post(std::function<void()> task)
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      tasks_.push_back(std::move(task));
    }
    wake_.notify_one();
  }

private:
  void run()
  {
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
    for (;;)
    {
      std::function<void()> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stop_ || !tasks_.empty(); });
        if (tasks_.empty())
          return;
        task = std::move(tasks_.front());
        tasks_.pop_front();
      }
      task();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stop_ = false;
  std::thread thread_;  ///< last: started once the rest is built
};
}  // namespace

void planInBackground(std::function<void()> task)
{
  static BackgroundPlanner planner;
  planner.post(std::move(task));
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
