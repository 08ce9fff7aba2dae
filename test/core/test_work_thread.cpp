// WorkThread: work done in order behind the caller, bounded, its error thrown where the caller
// would have met it, the caller free to stop early.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <vector>

#include "periodic_bias_compensation/common/work_thread.h"

namespace periodic_bias_compensation
{
// Every item is done, in the order handed, by the time finish() returns.
TEST(WorkThread, DoesEveryItemInOrder)
{
  std::vector<int> done;
  WorkThread<int> thread(2, [&done](int& item) { done.push_back(item); });
  for (int i = 0; i < 1000; ++i)
    thread.hand(i);
  thread.finish();
  ASSERT_EQ(done.size(), 1000u);
  for (int i = 0; i < 1000; ++i)
    EXPECT_EQ(done[i], i);
}

// hand() waits while `capacity` items wait: with the work held, one item in work and two waiting,
// a fourth hand() does not return until the work is let go.
TEST(WorkThread, HandWaitsWhileCapacityItemsWait)
{
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> started{ 0 };
  WorkThread<int> thread(2, [&](int&) {
    ++started;
    released.wait();
  });
  thread.hand(0);
  while (started.load() == 0)
    std::this_thread::yield();
  thread.hand(1);
  thread.hand(2);
  auto fourth = std::async(std::launch::async, [&thread] { thread.hand(3); });
  EXPECT_EQ(fourth.wait_for(std::chrono::milliseconds(200)), std::future_status::timeout);
  release.set_value();
  EXPECT_EQ(fourth.wait_for(std::chrono::seconds(60)), std::future_status::ready);
  fourth.get();
  thread.finish();
  EXPECT_EQ(started.load(), 4);
}

// An error stops the work: what waits is not done, and the next hand() (or finish()) throws it.
TEST(WorkThread, AnErrorStopsTheWorkAndIsThrownToTheCaller)
{
  std::vector<int> done;
  WorkThread<int> thread(1, [&done](int& item) {
    if (item == 3)
      throw std::runtime_error("disk full");
    done.push_back(item);
  });
  bool thrown = false;
  for (int i = 0; i < 100 && !thrown; ++i)
  {
    try
    {
      thread.hand(i);
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_STREQ(e.what(), "disk full");
      thrown = true;
    }
  }
  EXPECT_TRUE(thrown);
  EXPECT_THROW(thread.finish(), std::runtime_error);
  EXPECT_EQ(done, (std::vector<int>{ 0, 1, 2 }));
}

// Destroyed without finish() (the caller stopped on an error of its own): what waits is dropped,
// and the destructor returns once the item in work is done (let go half a second after the
// destructor began waiting for it).
TEST(WorkThread, DestroyedEarlyDropsWhatWaits)
{
  std::atomic<int> started{ 0 }, done{ 0 };
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::future<void> releasing;
  {
    WorkThread<int> thread(8, [&](int&) {
      ++started;
      released.wait();
      ++done;
    });
    for (int i = 0; i < 8; ++i)
      thread.hand(i);
    while (started.load() == 0)
      std::this_thread::yield();
    releasing = std::async(std::launch::async, [&release] {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      release.set_value();
    });
  }
  releasing.get();
  EXPECT_EQ(done.load(), 1);
}

// keep_done: the items done come back for the caller to reuse; never more than were handed.
TEST(WorkThread, KeepsTheItemsDoneForReuse)
{
  WorkThread<std::vector<int>> thread(
      1, [](std::vector<int>& item) { item.clear(); }, true);
  std::vector<int> buffer;
  buffer.reserve(1024);
  const int* storage = buffer.data();
  buffer.push_back(1);
  thread.hand(std::move(buffer));
  thread.finish();
  std::optional<std::vector<int>> back = thread.takeDone();
  ASSERT_TRUE(back.has_value());
  EXPECT_TRUE(back->empty());
  EXPECT_EQ(back->data(), storage) << "the same buffer";
  EXPECT_FALSE(thread.takeDone().has_value());
}

// What the work made comes back in the order handed, waitDone() waiting for it; once the thread
// has stopped on an error and nothing done is left, waitDone() throws the error.
TEST(WorkThread, WaitDoneGivesTheItemsDoneInOrderThenTheError)
{
  WorkThread<int> thread(
      4,
      [](int& item) {
        if (item < 0)
          throw std::runtime_error("unreadable");
        item *= 10;
      },
      true);
  for (int i = 1; i <= 3; ++i)
    thread.hand(i);
  EXPECT_EQ(thread.waitDone(), 10);
  EXPECT_EQ(thread.waitDone(), 20);
  thread.hand(-1);
  EXPECT_EQ(thread.waitDone(), 30);
  EXPECT_THROW(thread.waitDone(), std::runtime_error);
}
}  // namespace periodic_bias_compensation
