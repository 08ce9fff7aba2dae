#include "periodic_bias_compensation/ros/callback_thread.h"

#include <pthread.h>
#include <sched.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include <boost/make_shared.hpp>

namespace periodic_bias_compensation
{
namespace
{
/// How long the thread waits for a callback before it looks at running_ again [s].
constexpr double kWait = 0.1;

/// A function as a queue's callback.
class FunctionCallback : public ros::CallbackInterface
{
public:
  explicit FunctionCallback(std::function<void()> work) : work_(std::move(work))
  {
  }
  CallResult call() override
  {
    work_();
    return Success;
  }

private:
  std::function<void()> work_;
};
}  // namespace

CallbackThread::CallbackThread(const char* name)
  : thread_([this] {
      while (running_)
      {
        queue_.callAvailable(ros::WallDuration(kWait));
      }
    })
{
  char shortened[16] = {};
  std::strncpy(shortened, name, sizeof(shortened) - 1);
  pthread_setname_np(thread_.native_handle(), shortened);
}

bool setRealtimePriority(pthread_t thread, int priority, std::string* why)
{
  const int lowest = sched_get_priority_min(SCHED_FIFO);
  const int highest = sched_get_priority_max(SCHED_FIFO);
  if (priority < lowest || priority > highest)
  {
    *why = "priority " + std::to_string(priority) + " is outside SCHED_FIFO's " + std::to_string(lowest) + "-" +
           std::to_string(highest);
    return false;
  }
  sched_param param{};
  param.sched_priority = priority;
  const int error = pthread_setschedparam(thread, SCHED_FIFO, &param);
  if (error != 0)
  {
    *why = std::string("SCHED_FIFO refused: ") + std::strerror(error) +
           (error == EPERM ? " (the process needs CAP_SYS_NICE or an rtprio limit, limits.conf(5))" : "");
    return false;
  }
  return true;
}

bool pinToCpu(int cpu, std::string* why)
{
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  if (cpu >= 0 && cpu < CPU_SETSIZE)
    CPU_SET(cpu, &cpus);
  if (sched_setaffinity(0, sizeof(cpus), &cpus) != 0)
  {
    *why = "CPU " + std::to_string(cpu) + ": " + std::strerror(errno);
    return false;
  }
  return true;
}

void CallbackThread::post(std::function<void()> work)
{
  queue_.addCallback(boost::make_shared<FunctionCallback>(std::move(work)));
}

CallbackThread::~CallbackThread()
{
  running_ = false;
  queue_.disable();  // wakes the thread if it waits
  thread_.join();
}
}  // namespace periodic_bias_compensation
