// A callback queue served by a thread of its own. A subscription made on it reaches its callback
// with one thread wake-up: the thread that delivers the message (an in-process publisher, or
// roscpp's network thread) adds it to the queue and the queue's thread runs it. A nodelet
// manager's queues take two (its queue thread hands the nodelet's queue to a worker thread).
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <thread>

#include <pthread.h>

#include <ros/callback_queue.h>

namespace periodic_bias_compensation
{
/// Schedules `thread` first-in first-out at `priority` (SCHED_FIFO, 1-99): it then runs whenever
/// it has work, ahead of every ordinary thread of the machine. False with the reason in *why when
/// `priority` is out of range or the system refuses (a process needs CAP_SYS_NICE or an rtprio
/// limit, limits.conf(5)); the thread then keeps its scheduling.
bool setRealtimePriority(pthread_t thread, int priority, std::string* why);

/// Runs the calling thread, and every thread it starts from now on, on CPU `cpu` alone. False
/// with the reason in *why when the system refuses (no such CPU, or not allowed to this process).
bool pinToCpu(int cpu, std::string* why);

class CallbackThread
{
public:
  /// Starts the thread, named `name` (as top and perf show it; at most 15 characters kept).
  explicit CallbackThread(const char* name);
  /// Stops the thread after the callback it is running, if any; callbacks still queued are
  /// dropped. Shut the subscriptions made on queue() down first.
  ~CallbackThread();
  CallbackThread(const CallbackThread&) = delete;
  CallbackThread& operator=(const CallbackThread&) = delete;

  /// The free setRealtimePriority() on this thread.
  bool setRealtimePriority(int priority, std::string* why)
  {
    return periodic_bias_compensation::setRealtimePriority(thread_.native_handle(), priority, why);
  }

  /// Runs `work` on the thread, after the callbacks already queued.
  void post(std::function<void()> work);

  /// The queue to give a subscription (ros::SubscribeOptions::callback_queue).
  ros::CallbackQueue* queue()
  {
    return &queue_;
  }

private:
  ros::CallbackQueue queue_;
  std::atomic<bool> running_{ true };
  std::thread thread_;
};
}  // namespace periodic_bias_compensation
