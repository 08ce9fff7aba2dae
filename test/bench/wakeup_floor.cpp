// wakeup_floor: what the machine itself gives a thread that must answer each sample on time, with
// no ROS and no estimator: the floor under nodelet_benchmark's latencies. Run by scripts/bench.py,
// not a test.
//
//   wakeup_floor --rate HZ --duration S [--realtime-priority P] [--cpu N] [--spin]
//                [--cpu-wakeup-latency S]
//
// A ticking thread sleeps to each sample time k / HZ (absolute, steady clock) and then wakes a
// second thread that waits on a condition variable, as the harness's publisher wakes a nodelet's
// thread and that thread the harness's receiver. Measured over S seconds:
//  - `handoff`: from the notify to the woken thread running: one hop of a sample (a nodelet's
//    answer takes two); notifies that come while the waiter has not yet run count once, from the
//    first;
//  - `timer`: how late the ticking thread wakes from each sleep.
// With --spin, then, for S seconds more: a thread that never sleeps reads the steady clock; `spin`
// is the time between two consecutive reads (over 10 us: the thread's CPU taken from it, by the
// kernel, another thread or the hypervisor). Always at ordinary priority: a real-time thread that
// never sleeps is throttled by the kernel (sched_rt_runtime_us), which would be measured instead.
// With --realtime-priority P the two threads run SCHED_FIFO P (refused: an error before anything
// runs); with --cpu N every thread runs on CPU N. With --cpu-wakeup-latency S no CPU may take
// longer than S seconds to come out of idle while it runs (0: idle CPUs poll; refused without write
// access to /dev/cpu_dma_latency: an error before anything runs).
//
// Output: per measurement one line of key=value pairs on stdout:
//   floor=NAME rate=HZ samples=N p50_us=.. p99_us=.. max_us=.. over_200us=.. over_1ms=..
//   realtime_priority=P cpu=N cpu_wakeup_latency=S
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "latency_settings.h"
#include "periodic_bias_compensation/ros/callback_thread.h"
#include "periodic_bias_compensation/ros/cpu_wakeup_latency.h"
#include "periodic_bias_compensation/tools/command_line.h"

namespace pbc = periodic_bias_compensation;
using Clock = std::chrono::steady_clock;

namespace
{
struct Options
{
  double rate = 0.0;
  double duration = 0.0;
  long realtime_priority = 0;
  long cpu = -1;
  bool spin = false;
  double cpu_wakeup_latency = -1.0;  ///< [s]; < 0: no request
};

const char* kUsage =
    "usage: wakeup_floor --rate HZ --duration S [--realtime-priority P] [--cpu N] [--spin]\n"
    "                    [--cpu-wakeup-latency S]\n";

std::optional<Options> parseOptions(int argc, char** argv)
{
  Options o;
  pbc::CommandLine cli(kUsage);
  cli.number("--rate", &o.rate)
      .number("--duration", &o.duration)
      .integer("--realtime-priority", &o.realtime_priority)
      .integer("--cpu", &o.cpu)
      .flag("--spin", &o.spin)
      .number("--cpu-wakeup-latency", &o.cpu_wakeup_latency);
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if (!(o.rate > 0.0 && o.rate <= 100000.0) || !(o.duration > 0.0))
    throw pbc::UsageError("--rate (0 to 100 kHz) and --duration > 0 are required");
  if (o.realtime_priority < 0 || o.realtime_priority > 99)
    throw pbc::UsageError("--realtime-priority is 0 (ordinary) to 99");
  return o;
}

double microseconds(Clock::duration d)
{
  return std::chrono::duration<double, std::micro>(d).count();
}

/// One output line over `us`, which it sorts.
void report(const char* name, const Options& o, std::vector<double> us)
{
  std::sort(us.begin(), us.end());
  const auto at = [&](double q) { return us.empty() ? 0.0 : us[std::min(us.size() - 1, std::size_t(q * us.size()))]; };
  const auto over = [&](double limit) { return us.end() - std::upper_bound(us.begin(), us.end(), limit); };
  std::printf(
      "floor=%s rate=%g samples=%zu p50_us=%.1f p99_us=%.1f max_us=%.1f over_200us=%ld over_1ms=%ld "
      "realtime_priority=%ld cpu=%ld cpu_wakeup_latency=%g\n",
      name, o.rate, us.size(), at(0.5), at(0.99), us.empty() ? 0.0 : us.back(), static_cast<long>(over(200.0)),
      static_cast<long>(over(1000.0)), o.realtime_priority, o.cpu, o.cpu_wakeup_latency);
}

/// The ticking thread and the one it wakes: `handoff` and `timer`.
void tickAndHandOff(const Options& o)
{
  const long samples = static_cast<long>(o.duration * o.rate);
  std::vector<double> handoff, late;
  handoff.reserve(samples);
  late.reserve(samples);
  std::mutex mutex;
  std::condition_variable wake;
  long posted = 0, taken = 0;
  Clock::time_point notified;
  bool done = false;
  std::thread waiter([&] {
    std::unique_lock<std::mutex> lock(mutex);
    for (;;)
    {
      wake.wait(lock, [&] { return done || taken < posted; });
      if (taken < posted)
      {
        handoff.push_back(microseconds(Clock::now() - notified));
        taken = posted;
      }
      else
        return;
    }
  });
  std::string why;
  if (o.realtime_priority > 0 && !pbc::setRealtimePriority(waiter.native_handle(), o.realtime_priority, &why))
  {
    // Granted to this thread in main(): a refusal now is unexpected.
    std::cerr << "wakeup_floor: real-time priority refused to the waiting thread: " << why << "\n";
    std::exit(1);
  }
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.rate));
  const Clock::time_point start = Clock::now() + std::chrono::milliseconds(100);
  for (long k = 0; k < samples; ++k)
  {
    const Clock::time_point due = start + k * period;
    std::this_thread::sleep_until(due);
    const Clock::time_point woke = Clock::now();
    late.push_back(microseconds(woke - due));
    {
      // From the oldest notify the waiter has not taken: one it misses until the next is not lost.
      std::lock_guard<std::mutex> lock(mutex);
      if (taken == posted)
        notified = Clock::now();
      ++posted;
    }
    wake.notify_one();
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    done = true;
  }
  wake.notify_one();
  waiter.join();
  report("handoff", o, handoff);
  report("timer", o, late);
}

/// A thread that never sleeps: the gaps between its clock reads over 10 us.
void spin(const Options& o)
{
  std::vector<double> gaps;
  std::thread spinner([&] {
    const Clock::time_point end =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.duration));
    Clock::time_point last = Clock::now();
    while (last < end)
    {
      const Clock::time_point now = Clock::now();
      const double gap = microseconds(now - last);
      if (gap > 10.0)
        gaps.push_back(gap);
      last = now;
    }
  });
  const sched_param ordinary{};
  pthread_setschedparam(spinner.native_handle(), SCHED_OTHER, &ordinary);
  spinner.join();
  report("spin", o, gaps);
}
}  // namespace

int main(int argc, char** argv)
{
  Options options;
  pbc::CpuWakeupLatencyRequest wakeup_latency;  // held until the process ends
  try
  {
    const std::optional<Options> parsed = parseOptions(argc, argv);
    if (!parsed)
      return 0;
    options = *parsed;
    pbc::applyLatencySettings(options.cpu_wakeup_latency, options.cpu, options.realtime_priority, &wakeup_latency);
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "wakeup_floor: " << e.what() << "\n" << kUsage;
    return 2;
  }
  tickAndHandOff(options);
  if (options.spin)
    spin(options);
  return 0;
}
