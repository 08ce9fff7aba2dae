// The latency settings the latency benchmarks take from their command line (nodelet_benchmark,
// wakeup_floor): a CPU wake-up latency request, one CPU for the process, a real-time priority.
#pragma once

#include <pthread.h>

#include <string>

#include "periodic_bias_compensation/ros/callback_thread.h"
#include "periodic_bias_compensation/ros/cpu_wakeup_latency.h"
#include "periodic_bias_compensation/tools/command_line.h"

namespace periodic_bias_compensation
{
/// Before the process starts any thread (they inherit the CPU and the priority): holds a request
/// for `cpu_wakeup_latency` [s] in *request (none when negative), pins the process to `cpu` (none
/// when negative) and makes the calling thread SCHED_FIFO at `realtime_priority` (none at 0).
/// Refused, a UsageError naming the option (--cpu-wakeup-latency, --cpu, --realtime-priority).
inline void applyLatencySettings(double cpu_wakeup_latency, long long cpu, long long realtime_priority,
                                 CpuWakeupLatencyRequest* request)
{
  std::string why;
  if (cpu_wakeup_latency >= 0.0 && !request->request(cpu_wakeup_latency, &why))
    throw UsageError("--cpu-wakeup-latency: " + why);
  if (cpu >= 0 && !pinToCpu(static_cast<int>(cpu), &why))
    throw UsageError("--cpu: " + why);
  if (realtime_priority > 0 && !setRealtimePriority(pthread_self(), static_cast<int>(realtime_priority), &why))
    throw UsageError("--realtime-priority: " + why);
}
}  // namespace periodic_bias_compensation
