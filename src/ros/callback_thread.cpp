#include "periodic_bias_compensation/ros/callback_thread.h"

namespace periodic_bias_compensation
{
namespace
{
/// How long the thread waits for a callback before it looks at running_ again [s].
constexpr double kWait = 0.1;
}  // namespace

CallbackThread::CallbackThread()
  : thread_([this] {
      while (running_)
      {
        queue_.callAvailable(ros::WallDuration(kWait));
      }
    })
{
}

CallbackThread::~CallbackThread()
{
  running_ = false;
  queue_.disable();  // wakes the thread if it waits
  thread_.join();
}
}  // namespace periodic_bias_compensation
