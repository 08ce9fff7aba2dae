// The core's background threads: named, batch-scheduled (posting a task never hands the caller's
// core to them), the planning thread at nice 19 and the design thread at the caller's priority.
#include <gtest/gtest.h>

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>

#include <functional>
#include <future>
#include <memory>
#include <string>

#include "../../src/core/background.h"

namespace periodic_bias_compensation
{
namespace
{
struct ThreadState
{
  std::string name;
  int policy = -1;
  int nice = 0;
  bool other_thread = false;
};

/// What the thread that runs a task posted with `post` is, seen from the task.
ThreadState stateOfThreadOf(void (*post)(std::function<void()>))
{
  auto state = std::make_shared<std::promise<ThreadState>>();
  const pthread_t caller = pthread_self();
  post([state, caller] {
    ThreadState s;
    char name[16] = {};
    pthread_getname_np(pthread_self(), name, sizeof(name));
    s.name = name;
    s.policy = sched_getscheduler(0);
    s.nice = getpriority(PRIO_PROCESS, 0);
    s.other_thread = !pthread_equal(pthread_self(), caller);
    state->set_value(s);
  });
  return state->get_future().get();
}
}  // namespace

TEST(Background, ThePlanningThreadIsANamedBatchThreadAtNice19)
{
  const ThreadState s = stateOfThreadOf(planInBackground);
  EXPECT_TRUE(s.other_thread);
  EXPECT_EQ(s.name, "pbc_plan");
  EXPECT_EQ(s.policy, SCHED_BATCH);
  EXPECT_EQ(s.nice, 19);
}

TEST(Background, TheDesignThreadIsANamedBatchThreadAtTheCallersPriority)
{
  const int callers_nice = getpriority(PRIO_PROCESS, 0);
  const ThreadState s = stateOfThreadOf(designInBackground);
  EXPECT_TRUE(s.other_thread);
  EXPECT_EQ(s.name, "pbc_design");
  EXPECT_EQ(s.policy, SCHED_BATCH);
  EXPECT_EQ(s.nice, callers_nice);
}
}  // namespace periodic_bias_compensation
