// CallbackThread without a master: work posted to it runs on its own, named thread, in
// order, its destructor waits for the callback it is running, and a real-time priority is its
// thread's alone. The other latency settings beside it: a process pinned to one CPU, and a
// request for the CPUs' wake-up latency held while its object lives.
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <future>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "periodic_bias_compensation/ros/callback_thread.h"
#include "periodic_bias_compensation/ros/cpu_wakeup_latency.h"

namespace
{
using periodic_bias_compensation::CallbackThread;

std::string threadName()
{
  char name[16] = {};
  pthread_getname_np(pthread_self(), name, sizeof(name));
  return name;
}
}  // namespace

TEST(CallbackThread, RunsCallbacksInOrderOnItsOwnNamedThread)
{
  CallbackThread thread("pbc_test");
  std::mutex mutex;
  std::condition_variable done;
  std::vector<int> order;
  std::vector<std::thread::id> ids;
  std::vector<std::string> names;
  for (int i = 0; i < 5; ++i)
  {
    thread.post([&, i] {
      std::lock_guard<std::mutex> lock(mutex);
      order.push_back(i);
      ids.push_back(std::this_thread::get_id());
      names.push_back(threadName());
      done.notify_one();
    });
  }
  std::unique_lock<std::mutex> lock(mutex);
  ASSERT_TRUE(done.wait_for(lock, std::chrono::seconds(10), [&] { return order.size() == 5; }));
  EXPECT_EQ(order, (std::vector<int>{ 0, 1, 2, 3, 4 }));
  for (std::size_t i = 0; i < ids.size(); ++i)
  {
    EXPECT_NE(ids[i], std::this_thread::get_id());
    EXPECT_EQ(ids[i], ids[0]);
    EXPECT_EQ(names[i], "pbc_test");
  }
}

TEST(CallbackThread, LongNamesAreCutToWhatTheKernelKeeps)
{
  CallbackThread thread("a_name_longer_than_fifteen");
  std::promise<std::string> name;
  thread.post([&] { name.set_value(threadName()); });
  auto future = name.get_future();
  ASSERT_EQ(future.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  EXPECT_EQ(future.get(), "a_name_longer_t");
}

TEST(CallbackThread, DestructionWaitsForTheRunningCallback)
{
  std::atomic<bool> started{ false }, finished{ false };
  {
    CallbackThread thread("pbc_test");
    thread.post([&] {
      started = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      finished = true;
    });
    while (!started)
      std::this_thread::yield();
  }
  EXPECT_TRUE(finished);
}

namespace
{
/// The calling thread's scheduling policy and priority.
std::pair<int, int> scheduling()
{
  int policy = -1;
  sched_param param{};
  pthread_getschedparam(pthread_self(), &policy, &param);
  return { policy, param.sched_priority };
}

/// The scheduling of `thread`'s thread, read on it.
std::pair<int, int> schedulingOf(CallbackThread* thread)
{
  std::promise<std::pair<int, int>> seen;
  thread->post([&] { seen.set_value(scheduling()); });
  auto future = seen.get_future();
  EXPECT_EQ(future.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  return future.get();
}
}  // namespace

// Granted (CAP_SYS_NICE or an rtprio limit), the thread runs SCHED_FIFO at that priority and the
// caller keeps its own scheduling; refused, the thread keeps its scheduling and the reason says
// why. Out-of-range priorities are refused before the system is asked.
TEST(CallbackThread, RealtimePriorityIsTheThreadsOwnOrRefusedWithTheReason)
{
  CallbackThread thread("pbc_test");
  const std::pair<int, int> before = schedulingOf(&thread);
  const std::pair<int, int> caller = scheduling();
  EXPECT_EQ(before.first, SCHED_OTHER);
  std::string why;
  for (int out_of_range : { 0, -1, 100 })
  {
    EXPECT_FALSE(thread.setRealtimePriority(out_of_range, &why));
    EXPECT_NE(why.find("outside SCHED_FIFO's 1-99"), std::string::npos) << why;
    EXPECT_EQ(schedulingOf(&thread), before);
  }
  why.clear();
  const bool granted = thread.setRealtimePriority(10, &why);
  if (granted)
  {
    EXPECT_TRUE(why.empty()) << why;
    EXPECT_EQ(schedulingOf(&thread), std::make_pair(static_cast<int>(SCHED_FIFO), 10));
  }
  else
  {
    EXPECT_NE(why.find("SCHED_FIFO refused: "), std::string::npos) << why;
    EXPECT_EQ(schedulingOf(&thread), before);
  }
  EXPECT_EQ(scheduling(), caller);
}

// pinToCpu: the calling thread and those it starts run on that CPU alone; a CPU the machine does
// not have is refused with the reason, the thread's CPUs unchanged.
TEST(CallbackThread, PinToCpuHoldsTheCallerAndItsThreads)
{
  std::thread([] {
    cpu_set_t before;
    ASSERT_EQ(sched_getaffinity(0, sizeof(before), &before), 0);
    std::string why;
    EXPECT_FALSE(periodic_bias_compensation::pinToCpu(CPU_SETSIZE + 1, &why));
    EXPECT_NE(why.find("CPU"), std::string::npos) << why;
    cpu_set_t unchanged;
    ASSERT_EQ(sched_getaffinity(0, sizeof(unchanged), &unchanged), 0);
    EXPECT_TRUE(CPU_EQUAL(&before, &unchanged));

    int allowed = 0;
    while (!CPU_ISSET(allowed, &before))
      ++allowed;
    ASSERT_TRUE(periodic_bias_compensation::pinToCpu(allowed, &why)) << why;
    for (int round = 0; round < 2; ++round)
    {
      cpu_set_t now;
      ASSERT_EQ(sched_getaffinity(0, sizeof(now), &now), 0);
      EXPECT_EQ(CPU_COUNT(&now), 1);
      EXPECT_TRUE(CPU_ISSET(allowed, &now));
      if (round == 0)
      {
        // A thread started now inherits it.
        cpu_set_t child;
        std::thread([&child] { sched_getaffinity(0, sizeof(child), &child); }).join();
        EXPECT_TRUE(CPU_EQUAL(&child, &now));
      }
    }
  }).join();
}

// A wake-up latency request out of range, or on a device that cannot be opened, is refused with
// the reason and holds nothing. Where this process may read and write the kernel's device (root),
// the kernel honours the strictest request held, and the limit before returns once both are
// withdrawn.
TEST(CpuWakeupLatency, RequestHeldWhileItsObjectLivesOrRefusedWithTheReason)
{
  using periodic_bias_compensation::cpuWakeupLatencyLimit;
  using periodic_bias_compensation::CpuWakeupLatencyRequest;
  CpuWakeupLatencyRequest first;
  std::string why;
  for (double out_of_range : { -1e-6, 1.5, std::nan("") })
  {
    EXPECT_FALSE(first.request(out_of_range, &why));
    EXPECT_NE(why.find("is outside [0, 1] s"), std::string::npos) << why;
    EXPECT_FALSE(first.held());
  }
  const std::string missing = "/nonexistent/cpu_dma_latency";
  EXPECT_FALSE(first.request(0.0, &why, missing));
  EXPECT_NE(why.find("cannot open " + missing + " for writing: "), std::string::npos) << why;
  EXPECT_FALSE(first.held());
  EXPECT_FALSE(cpuWakeupLatencyLimit(missing).has_value());

  const std::optional<double> before = cpuWakeupLatencyLimit();
  if (!before)
    GTEST_SKIP() << "cannot read " << periodic_bias_compensation::kCpuWakeupLatencyDevice
                 << " (it takes root): the kernel's limit not checked";
  if (!first.request(20e-6, &why))
    GTEST_SKIP() << "wake-up latency request refused, the kernel's limit not checked: " << why;
  EXPECT_TRUE(first.held());
  EXPECT_DOUBLE_EQ(*cpuWakeupLatencyLimit(), std::min(*before, 20e-6));
  {
    CpuWakeupLatencyRequest second;
    ASSERT_TRUE(second.request(0.0, &why)) << why;
    EXPECT_DOUBLE_EQ(*cpuWakeupLatencyLimit(), 0.0);
    ASSERT_TRUE(second.request(1e-3, &why)) << why;  // replaces its own request
    EXPECT_DOUBLE_EQ(*cpuWakeupLatencyLimit(), std::min(*before, 20e-6));
  }
  first.release();
  EXPECT_FALSE(first.held());
  EXPECT_DOUBLE_EQ(*cpuWakeupLatencyLimit(), *before);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
