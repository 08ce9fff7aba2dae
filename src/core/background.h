// The core's background threads (internal to the core library): work that a sample's call
// would otherwise pay for in milliseconds runs there, and the caller picks up its result later.
#pragma once

#include <functional>

namespace periodic_bias_compensation
{
/// Runs `task` on the core's planning thread (one per process, at nice 19, so that it leaves the
/// core to the threads that feed samples), in the order given.
void planInBackground(std::function<void()> task);

/// Runs `task` on the core's design thread (one per process, at the caller's priority: a caller
/// waits for its result at a set sample), in the order given.
void designInBackground(std::function<void()> task);

}  // namespace periodic_bias_compensation
