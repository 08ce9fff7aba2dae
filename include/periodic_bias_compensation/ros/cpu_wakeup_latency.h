// How fast an idle CPU must answer a wake-up, asked of Linux for as long as an object lives.
#pragma once

#include <optional>
#include <string>

namespace periodic_bias_compensation
{
/// The device through which Linux takes CPU wake-up latency requests (PM QoS, a 32-bit count of
/// microseconds written to it; each open file is one request, withdrawn when it is closed).
constexpr const char* kCpuWakeupLatencyDevice = "/dev/cpu_dma_latency";

/// A request that no CPU of the machine take longer than a given time to come out of idle, held
/// until release() or destruction (or the process's end). Linux then keeps idle CPUs out of the
/// idle states slower than that to leave; at 0 they poll instead of halting: a thread woken by
/// another starts at once, at the price of the power an idle CPU saves. The request is the whole
/// machine's, not the process's: the strictest of all requests held is what the kernel honours.
class CpuWakeupLatencyRequest
{
public:
  CpuWakeupLatencyRequest() = default;
  ~CpuWakeupLatencyRequest();
  CpuWakeupLatencyRequest(const CpuWakeupLatencyRequest&) = delete;
  CpuWakeupLatencyRequest& operator=(const CpuWakeupLatencyRequest&) = delete;

  /// Asks for at most `latency` [s] (rounded to the microsecond; 0 to 1 s), replacing any request
  /// this object held. False with the reason in *why when `latency` is out of range or `device`
  /// cannot be written (writing /dev/cpu_dma_latency takes root, or a udev rule granting it);
  /// the request held before, if any, is then withdrawn.
  bool request(double latency, std::string* why, const std::string& device = kCpuWakeupLatencyDevice);

  /// Withdraws the request, if one is held.
  void release();

  bool held() const
  {
    return fd_ >= 0;
  }

private:
  int fd_ = -1;
};

/// The limit the kernel honours now, all requests combined [s]; nothing when `device` cannot be
/// read (reading it also takes root). With no request held it is the kernel's "no limit"
/// (2000 s).
std::optional<double> cpuWakeupLatencyLimit(const std::string& device = kCpuWakeupLatencyDevice);
}  // namespace periodic_bias_compensation
