// Ctrl-C: the command installs a SIGINT handler that calls RequestInterrupt(); long loops
// (runs, sweeps, annealing, rendering) poll InterruptRequested() between steps and stop
// cleanly, throwing Interrupted with where they were, after their finished files are kept.
// A second Ctrl-C is the default action again (the handler is one-shot), for a stuck process.
#pragma once

#include <atomic>

namespace wobble {

namespace detail {
inline std::atomic<bool>& InterruptFlag() {
  static std::atomic<bool> flag{false};
  return flag;
}
}  // namespace detail

// Async-signal-safe (a lock-free atomic store).
inline void RequestInterrupt() { detail::InterruptFlag().store(true, std::memory_order_relaxed); }
inline bool InterruptRequested() { return detail::InterruptFlag().load(std::memory_order_relaxed); }
inline void ClearInterrupt() { detail::InterruptFlag().store(false, std::memory_order_relaxed); }

}  // namespace wobble
