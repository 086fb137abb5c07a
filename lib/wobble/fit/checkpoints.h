// How a rollout gradient (adjoint.h) gets the forward run's states back in its
// backward sweep: kept whole, or recomputed an interval at a time from checkpoints.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace wobble::fit {

// The memory a gradient may keep for its whole forward run (every state, and in 3D every
// step's tape) before it checkpoints instead: 4 MiB holds about 4,500 steps of a 2D table
// (about 0.9 kB a state) and 600 of a 3D chair (about 7 kB a state and tape). Kept whole,
// a run saves the checkpoints' extra simulation but is slower once it leaves the caches and
// the storage a thread keeps between gradients (adjoint_sweep.h): on adjoint_bench the
// chair's whole run was 27 % faster than ⌈√steps⌉ checkpoints at 342 steps (2.4 MB) and
// 7–10 % slower at 3,334 steps (23 MB).
constexpr std::size_t kWholeRunMemoryBudget = std::size_t(4) << 20;

// Values of a gradient's checkpoint_interval besides a positive interval.
constexpr int kCheckpointAuto = 0;   // the whole run when it fits the budget, else ⌈√steps⌉
constexpr int kCheckpointSqrt = -1;  // ⌈√steps⌉: about 2√steps states held, one more simulation

// The interval a gradient of `steps` steps uses: `requested` when > 0; for kCheckpointAuto,
// `steps` (no checkpoints: nothing is recomputed, a gradient costs one simulation less) when
// steps × bytes_per_step fits in `budget`, ⌈√steps⌉ otherwise; for kCheckpointSqrt (or any
// other negative value), ⌈√steps⌉.
inline int CheckpointInterval(int steps, int requested, std::size_t bytes_per_step,
                              std::size_t budget = kWholeRunMemoryBudget) {
  if (requested > 0) return requested;
  const int sqrt_steps = std::max(1, int(std::ceil(std::sqrt(double(std::max(steps, 0))))));
  if (requested < 0) return sqrt_steps;
  const double whole = double(std::max(steps, 0)) * double(bytes_per_step);
  return whole <= double(budget) ? std::max(steps, 1) : sqrt_steps;
}

}  // namespace wobble::fit
