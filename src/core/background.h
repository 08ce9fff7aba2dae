// The core's background threads (internal to the core library): work that a sample's call
// would otherwise pay for in milliseconds runs there, and the caller picks up its result later.
#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <memory>

namespace periodic_bias_compensation
{
/// Runs `task` on the core's planning thread (one per process, at nice 19, so that it leaves the
/// core to the threads that feed samples), in the order given. The core's threads are batch
/// threads (SCHED_BATCH): posting a task never hands the caller's core to them.
void planInBackground(std::function<void()> task);

/// Runs `task` on the core's design thread (one per process, at the caller's priority: a caller
/// waits for its result at a set sample), started in the order given (the oldest not started may
/// be taken by a waiting caller instead, designQueuedHere()).
void designInBackground(std::function<void()> task);

/// Runs the oldest design task the design thread has not started on the calling thread, so that
/// a caller that must wait for a design makes another meanwhile (offline, where samples come
/// faster than designs, the two threads then design side by side); false when none is queued.
bool designQueuedHere();

/// `work` on the design thread (`background`) or at once on the calling thread; its result.
template <typename Work>
auto designTask(Work work, bool background) -> std::shared_future<decltype(work())>
{
  auto task = std::make_shared<std::packaged_task<decltype(work())()>>(std::move(work));
  std::shared_future<decltype(work())> result = task->get_future().share();
  if (background)
    designInBackground([task] { (*task)(); });
  else
    (*task)();
  return result;
}

/// The result of a designTask(), waited for: the design tasks still queued are made here meanwhile.
template <typename T>
const T& awaitDesign(const std::shared_future<T>& result)
{
  while (result.wait_for(std::chrono::seconds(0)) != std::future_status::ready && designQueuedHere())
  {
  }
  return result.get();
}

}  // namespace periodic_bias_compensation
