#include "periodic_bias_compensation/ros/cpu_wakeup_latency.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace periodic_bias_compensation
{
namespace
{
/// The largest request taken [s]: beyond the slowest idle state of any machine.
constexpr double kLongestRequest = 1.0;
}  // namespace

CpuWakeupLatencyRequest::~CpuWakeupLatencyRequest()
{
  release();
}

bool CpuWakeupLatencyRequest::request(double latency, std::string* why, const std::string& device)
{
  release();
  if (!(latency >= 0.0 && latency <= kLongestRequest))
  {
    char given[32];
    std::snprintf(given, sizeof(given), "%g", latency);
    *why = std::string("CPU wake-up latency ") + given + " s is outside [0, 1] s";
    return false;
  }
  const int fd = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0)
  {
    const int error = errno;
    *why = "cannot open " + device + " for writing: " + std::strerror(error) +
           (error == EACCES || error == EPERM ? " (it takes root, or a udev rule granting write access)" : "");
    return false;
  }
  const auto microseconds = static_cast<std::int32_t>(std::lround(latency * 1e6));
  if (::write(fd, &microseconds, sizeof(microseconds)) != static_cast<ssize_t>(sizeof(microseconds)))
  {
    *why = "writing " + device + " failed: " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  fd_ = fd;
  return true;
}

void CpuWakeupLatencyRequest::release()
{
  if (fd_ >= 0)
  {
    ::close(fd_);
    fd_ = -1;
  }
}

std::optional<double> cpuWakeupLatencyLimit(const std::string& device)
{
  const int fd = ::open(device.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return std::nullopt;
  std::int32_t microseconds = 0;
  const bool read = ::read(fd, &microseconds, sizeof(microseconds)) == static_cast<ssize_t>(sizeof(microseconds));
  ::close(fd);
  if (!read)
    return std::nullopt;
  return microseconds * 1e-6;
}
}  // namespace periodic_bias_compensation
