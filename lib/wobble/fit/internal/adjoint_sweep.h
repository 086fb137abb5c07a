// What the 2D and 3D adjoints (adjoint.h, adjoint3.h) share (not public): the Jets of their
// per-step products and the checkpointed forward run and backward sweep.
#pragma once

#include <ceres/jet.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace wobble::fit::internal {

// Inputs differentiated per Jet pass of a step's vector–Jacobian product.
constexpr int kAdjointChunk = 16;
using AdjointJet = ceres::Jet<double, kAdjointChunk>;

// Input i as a Jet whose derivative part is the unit vector of i when i is in the chunk that
// starts at `offset`, and zero otherwise.
inline AdjointJet Seed(double value, int i, int offset) {
  AdjointJet x(value);
  if (i >= offset && i < offset + kAdjointChunk) x.v[i - offset] = 1.0;
  return x;
}

// g[offset + k] += λ ∂y/∂(input offset + k) for the inputs of the chunk.
inline void Pull(const AdjointJet& y, double lambda, int offset, Eigen::VectorXd* g) {
  if (lambda == 0.0) return;
  const int n = std::min(kAdjointChunk, int(g->size()) - offset);
  for (int k = 0; k < n; ++k) (*g)[offset + k] += lambda * y.v[k];
}

// Sets *why to which step failed and why; returns false.
inline bool StepFailed(int n, const std::string& what, std::string* why) {
  *why = "step " + std::to_string(n) + " failed: " + what;
  return false;
}

// The plain cost Σ_n stage(n, state_n) of a rollout from `state`, for n = 0 … steps, with
// step(n, &state) → bool between; +∞ when a step fails.
template <class State, class Step, class Stage>
double PlainRolloutCost(int steps, State state, const Step& step, const Stage& stage) {
  double total = 0.0;
  for (int n = 0;; ++n) {
    total += stage(n, state);
    if (n == steps) return total;
    if (!step(n, &state)) return std::numeric_limits<double>::infinity();
  }
}

// One forward run keeping a checkpoint every `interval` steps, then the backward sweep, one
// interval at a time recomputed from its checkpoint, so about 2√steps states are held at once
// for √steps intervals (*states_held: the most). When one interval is the whole run, the
// forward run is that interval's recompute: every state (and tape) is kept from the start and
// no step is taken twice. On entry *lambda is the zero adjoint of a state; on return, λ_0.
//   step(n, &state) → bool       advances state n to n + 1
//   recompute(n, &state) → bool  the same, where the product can keep what the step computed
//                                (3D: StepTape3): in the backward sweep's recompute of an
//                                interval (steps begin … end − 2 of it, in order), or for every
//                                step, in order, when the interval is the whole run
//   vjp(n, state, next, λ_{n+1}, &λ_n) → bool
//   stage(n, state, &λ)          adds ℓ_n's value to the cost and its gradient to λ
// Returns false as soon as step or vjp does (they say why).
template <class State, class Adjoint, class Step, class Recompute, class Vjp, class Stage>
bool CheckpointedAdjointSweep(int steps, int interval, const State& start, Adjoint* lambda, const Step& step,
                              const Recompute& recompute, const Vjp& vjp, const Stage& stage, int* states_held) {
  const bool whole = steps > 0 && interval >= steps;
  std::vector<State> checkpoints, segment;
  State last = start;
  if (whole) {
    checkpoints.push_back(start);
    segment.reserve(size_t(std::max(steps, 1)));
    segment.push_back(start);
    for (int n = 0; n < steps; ++n) {
      if (n + 1 < steps) segment.push_back(segment.back());
      State* after = n + 1 < steps ? &segment.back() : &last;
      if (n + 1 == steps) last = segment.back();
      if (!recompute(n, after)) return false;
    }
  } else {
    for (int n = 0; n < steps; ++n) {
      if (n % interval == 0) checkpoints.push_back(last);
      if (!step(n, &last)) return false;
    }
  }
  stage(steps, last, lambda);
  Adjoint before = *lambda;
  for (int c = int(checkpoints.size()) - 1; c >= 0; --c) {
    const int begin = c * interval, end = std::min(steps, begin + interval);
    if (!whole) {
      segment.assign(1, checkpoints[size_t(c)]);
      for (int n = begin; n + 1 < end; ++n) {
        segment.push_back(segment.back());
        if (!recompute(n, &segment.back())) return false;
      }
    }
    *states_held = std::max(*states_held, int(checkpoints.size() + segment.size()));
    for (int n = end - 1; n >= begin; --n) {
      const State& state = segment[size_t(n - begin)];
      // state n + 1: in this interval, or the next interval's checkpoint, or the last state
      const State& next = n + 1 < end                          ? segment[size_t(n + 1 - begin)]
                          : c + 1 < int(checkpoints.size()) ? checkpoints[size_t(c + 1)]
                                                              : last;
      if (!vjp(n, state, next, *lambda, &before)) return false;
      stage(n, state, &before);
      std::swap(*lambda, before);
    }
  }
  return true;  // with no step, the start was the last state and its stage is in
}

}  // namespace wobble::fit::internal
