// A thread of its own that does work handed to it, in order, behind the thread that hands it:
// writing a bag while the next messages are compensated. Header only, standard library only.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

namespace periodic_bias_compensation
{
/// Runs `work` on each item handed to it, in the order handed, in a thread of its own, with at
/// most `capacity` items waiting: hand() waits while that many do, so the items in flight (and
/// their memory) are bounded. An exception thrown by `work` stops the thread and drops what waits;
/// the next hand() or finish() throws it, so the caller stops where a single loop would have. The
/// items `work` is done with are kept for the caller, in order (takeDone(), waitDone()): to reuse
/// their buffers, or as what the work made (a batch read ahead), when `keep_done` is set.
///
/// Threading: every call takes the one lock; the items may be handed from one thread and taken
/// done from another (a reader's batches, handed back by the thread that writes them). Nothing
/// may be handed once finish() is called.
template <typename T>
class WorkThread
{
public:
  using Work = std::function<void(T&)>;

  WorkThread(std::size_t capacity, Work work, bool keep_done = false)
    : capacity_(capacity > 0 ? capacity : 1), keep_done_(keep_done), work_(std::move(work)), thread_([this] { run(); })
  {
  }
  /// Stops at once, what still waits undone (the caller stopped early, on an error of its own), and
  /// waits for the item in work.
  ~WorkThread()
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      abandoned_ = true;
    }
    changed_.notify_all();
    if (thread_.joinable())
      thread_.join();
  }
  WorkThread(const WorkThread&) = delete;
  WorkThread& operator=(const WorkThread&) = delete;

  /// Queues an item, waiting while `capacity` wait; throws what stopped the thread, if anything did.
  void hand(T item)
  {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return waiting_.size() < capacity_ || error_; });
      if (error_)
        std::rethrow_exception(error_);
      waiting_.push_back(std::move(item));
    }
    changed_.notify_all();
  }

  /// The oldest item `work` is done with, if one is kept (keep_done); never waits.
  std::optional<T> takeDone()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (done_.empty())
      return std::nullopt;
    std::optional<T> item(std::move(done_.front()));
    done_.pop_front();
    return item;
  }

  /// The oldest item `work` is done with (keep_done), waiting for one; throws what stopped the
  /// thread, if anything did, once none is left. Not after finish(): nothing more would come.
  T waitDone()
  {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return !done_.empty() || error_; });
    if (done_.empty())
      std::rethrow_exception(error_);
    T item = std::move(done_.front());
    done_.pop_front();
    return item;
  }

  /// Waits until every item handed is done and the thread has ended; throws what stopped it, if
  /// anything did. Nothing may be handed after.
  void finish()
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      finishing_ = true;
    }
    changed_.notify_all();
    if (thread_.joinable())
      thread_.join();
    if (error_)
      std::rethrow_exception(error_);
  }

private:
  void run()
  {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;)
    {
      changed_.wait(lock, [this] { return !waiting_.empty() || finishing_ || abandoned_; });
      if (waiting_.empty() || abandoned_)
        return;
      T item = std::move(waiting_.front());
      waiting_.pop_front();
      lock.unlock();
      changed_.notify_all();
      std::exception_ptr error;
      try
      {
        work_(item);
      }
      catch (...)
      {
        error = std::current_exception();
      }
      lock.lock();
      if (error)
      {
        error_ = error;
        waiting_.clear();
        changed_.notify_all();
        return;
      }
      if (keep_done_)
      {
        done_.push_back(std::move(item));
        changed_.notify_all();
      }
    }
  }

  const std::size_t capacity_;
  const bool keep_done_;
  Work work_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<T> waiting_;   ///< oldest first
  std::deque<T> done_;      ///< oldest first
  bool finishing_ = false;  ///< finish(): what waits is still done
  bool abandoned_ = false;  ///< the destructor: nothing more is done
  std::exception_ptr error_;
  std::thread thread_;  ///< last: started once the rest is built
};
}  // namespace periodic_bias_compensation
