#include "background.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

namespace periodic_bias_compensation
{
namespace
{
/// A thread named `name` with a queue of tasks, run one at a time in the order posted; at `nice`
/// (0: the priority of the thread that started it), scheduled as a batch thread (SCHED_BATCH): it
/// keeps its share of the processor, but waking it never preempts the thread that posted the
/// task. As an ordinary thread it would: woken after sleeping, the scheduler favours it, and the
/// sample's call that posted a task lost its core for milliseconds (docs/benchmarks.md, "Nodelet
/// latency, where the time goes").
class BackgroundThread
{
public:
  BackgroundThread(const char* name, int nice) : nice_(nice), thread_([this] { run(); })
  {
    pthread_setname_np(thread_.native_handle(), name);
  }
  ~BackgroundThread()
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
  /// Runs the oldest task not yet started on the calling thread; false when none is queued.
  bool runOne()
  {
    std::function<void()> task;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (tasks_.empty())
        return false;
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    task();
    return true;
  }

private:
  void run()
  {
    // Both are allowed to any thread; where refused, the thread runs as an ordinary one.
    const sched_param batch{};
    pthread_setschedparam(pthread_self(), SCHED_BATCH, &batch);
    if (nice_ != 0)
      setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice_);
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

  const int nice_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stop_ = false;
  std::thread thread_;  ///< last: started once the rest is built
};

BackgroundThread& designer()
{
  static BackgroundThread thread("pbc_design", 0);
  return thread;
}
}  // namespace

void planInBackground(std::function<void()> task)
{
  static BackgroundThread planner("pbc_plan", 19);
  planner.post(std::move(task));
}

void designInBackground(std::function<void()> task)
{
  designer().post(std::move(task));
}

bool designQueuedHere()
{
  return designer().runOne();
}

}  // namespace periodic_bias_compensation
