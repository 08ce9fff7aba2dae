#include "periodic_bias_compensation/ros/callback_thread.h"

#include <pthread.h>

#include <cstring>
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
