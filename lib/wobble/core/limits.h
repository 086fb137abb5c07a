// Work and memory limits: a run that would exceed one stops before it starts with a
// LimitExceeded naming the limit and how to raise it (scripts: `set max_steps N`,
// `set max_record_mb N`; the CLI: --max-steps, --max-record-mb). Counts derived from input
// numbers (steps from a duration and dt, samples from a step, grid sizes) go through
// CheckedCount, so that no double turns into an overflowing integer.
#pragma once

#include <string>

namespace wobble {

// Fixed bounds on counts people set (a limit above can be raised; these are sanity bounds).
constexpr long kMaxStepsLimit = 1'000'000'000'000'000;  // max_steps itself: 10^15 steps
constexpr long kMaxThreads = 256;                        // worker threads of a synthesis
constexpr long kMaxLinearPoints = 1'000'000;             // mass points of a Witkin & Welch body

struct Limits {
  // Steps one command may simulate: one run (simul, keyframe, simulate --duration), or all
  // the trials of one anneal/cmaes together.
  long max_steps = 20'000'000;
  // Memory the samples a script or scene keeps (every run's record) may use, in MiB.
  double max_record_mb = 2048.0;
};

// round(value) as a count in [min_count, max_count], or an InputError naming `what`: for a
// non-finite value, one below min_count, or one above max_count (where `raise_hint`, if not
// empty, says how to allow more, e.g. "raise it with `set max_steps N`").
long CheckedCount(double value, long min_count, long max_count, const std::string& what,
                  const std::string& raise_hint = "");

// The steps of a run of `duration` at `dt`: round(duration/dt), checked against
// limits.max_steps (LimitExceeded) and for finite, positive dt and non-negative duration.
long RunSteps(double duration, double dt, const Limits& limits, const std::string& hint);

// Refuses (LimitExceeded) a record that would keep `values` doubles more than the limit.
void CheckRecordSize(double values, const Limits& limits, const std::string& hint);

}  // namespace wobble
