// The adjoint of adjoint.h (not public): the Jets of the per-step products, the checkpointed
// forward run and backward sweep, and the one gradient and cost of a rollout of either
// dimension over the dimension's own step piece (AdjointStep<Dim>: adjoint_plane.cc in 2D,
// adjoint_space.cc in 3D).
#pragma once

#include <ceres/jet.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "wobble/fit/adjoint.h"

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

using ContactKey = std::pair<int, int>;  // (point, face): a contact's identity across steps

// λ of one state: ∂cost/∂z in the state's tangent coordinates (adjoint.h), and ∂cost/∂(the
// anchor of each contact).
template <int Dim> struct StateAdjoint {
  Eigen::VectorXd z;
  std::map<ContactKey, Eigen::Matrix<double, Dim, 1>> anchor;
};

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
//                                (3D: StepTape): in the backward sweep's recompute of an
//                                interval (steps begin … end − 2 of it, in order), or for every
//                                step, in order, when the interval is the whole run
//   vjp(n, state, next, λ_{n+1}, &λ_n) → bool
//   stage(n, state, &λ)          adds ℓ_n's value to the cost and its gradient to λ
// Returns false as soon as step or vjp does (they say why).
// `checkpoints` and `segment` are the sweep's storage, emptied here (their capacity is kept:
// SweepBuffers below), and reserved to their final sizes, so no state is copied by a vector
// growing.
template <class State, class Adjoint, class Step, class Recompute, class Vjp, class Stage>
bool CheckpointedAdjointSweep(int steps, int interval, const State& start, Adjoint* lambda, const Step& step,
                              const Recompute& recompute, const Vjp& vjp, const Stage& stage, int* states_held,
                              std::vector<State>* checkpoints_storage, std::vector<State>* segment_storage) {
  const bool whole = steps > 0 && interval >= steps;
  std::vector<State>& checkpoints = *checkpoints_storage;
  std::vector<State>& segment = *segment_storage;
  checkpoints.clear();
  segment.clear();
  checkpoints.reserve(whole ? 1 : size_t((steps + interval - 1) / std::max(interval, 1)));
  segment.reserve(size_t(std::max(std::min(interval, steps), 1)));
  State last = start;
  if (whole) {
    checkpoints.push_back(start);
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

// The storage of a gradient's sweep (checkpointed states, an interval's states and tapes),
// kept per thread from one gradient to the next: an optimizer asks for thousands, and fresh
// storage costs a page fault per 4 kB touched (a 3D chair's ⌈√steps⌉ tapes are about 400 kB,
// 10 % of its gradient, measured on adjoint_bench's GradientChair/10000/1/-1). Storage above
// kKeptBytes (twice the whole-run budget of checkpoints.h, so a default gradient's storage is
// always kept) is given back after each gradient: a long run with an interval asked for is
// not held on to.
// A gradient taken inside another on the same thread (from a stage cost) uses storage of its own.
template <class State, class Tape> struct SweepBuffers {
  static constexpr size_t kKeptBytes = 2 * kWholeRunMemoryBudget;
  std::vector<State> checkpoints, segment;
  std::vector<Tape> tapes;
  bool in_use = false;
  size_t Bytes() const {
    return (checkpoints.capacity() + segment.capacity()) * sizeof(State) + tapes.capacity() * sizeof(Tape);
  }
  void Release() {
    if (Bytes() > kKeptBytes) *this = SweepBuffers();
    in_use = false;
  }
};

// Each dimension's step piece: AdjointStep<2> (adjoint_plane.cc), AdjointStep<3> (adjoint_space.cc).
template <int Dim> class AdjointStep;

// The one rollout of either dimension over its step piece `Piece` (internal::AdjointStep<Dim>):
//   Piece(body, rollout)                     the body with its own mode forces off, the gains
//   kWhat                                    how its errors begin ("rollout", "3D rollout")
//   CheckStartSizes(body, start, fail), StartFinite(start), CheckStartValid(start, fail)
//   Start()                                  the start state, contacts found
//   Advance(n, &s, &why) → bool              a plain step
//   Tape, kTaped                             what Record keeps of a step for Vjp (3D), or not (2D)
//   Record(n, &s, &tape, &why) → bool        a step keeping its tape (kTaped only)
//   StepBytes(start)                         a kept step's memory (checkpoints.h's budget)
//   Vjp(n, s, next, tape or null, λ', &λ, &g, &why) → bool   the step's product (sets g's
//                                            targets column, adds the gains' part)
//   StartVjp(λ_0, &dz0)                      the start's contact update pulled back
template <class Piece, int Dim> void CheckRollout(const BodyModelN<Dim>& body, const ControlledRolloutN<Dim>& r) {
  const int D = body.num_modes();
  auto fail = [](const std::string& what) { throw std::invalid_argument(std::string(Piece::kWhat) + ": " + what); };
  if (r.integrator != Integrator::kThesis && r.integrator != Integrator::kSymplecticEuler)
    fail("the adjoint takes the thesis and symplectic integrators, not " + IntegratorName(r.integrator));
  if (!(r.dt > 0.0) || !std::isfinite(r.dt)) fail("dt must be positive and finite");
  Piece::CheckStartSizes(body, r.start, fail);
  if (r.stiffness.size() != D || r.damping.size() != D) fail("stiffness and damping need one value per mode");
  if (r.targets.rows() != D) fail("targets need one row per mode (" + std::to_string(D) + ")");
  if (!Piece::StartFinite(r.start) || !r.stiffness.allFinite() || !r.damping.allFinite() || !r.targets.allFinite())
    fail("every number must be finite");
  Piece::CheckStartValid(r.start, fail);
}

template <class Piece, int Dim>
double RolloutCostOf(const BodyModelN<Dim>& body, const ControlledRolloutN<Dim>& rollout, const StageCostN<Dim>& cost) {
  CheckRollout<Piece>(body, rollout);
  const Piece r(body, rollout);
  Eigen::VectorXd dz(StateTangentSize(body));
  std::string why;
  return PlainRolloutCost(
      rollout.steps(), r.Start(), [&](int n, BodyState<Dim, double>* s) { return r.Advance(n, s, &why); },
      [&](int n, const BodyState<Dim, double>& s) {
        dz.setZero();
        return cost(n, s, &dz);
      });
}

template <class Piece, int Dim>
RolloutGradient RolloutGradientOf(const BodyModelN<Dim>& body, const ControlledRolloutN<Dim>& rollout,
                                  const StageCostN<Dim>& cost, int checkpoint_interval) {
  CheckRollout<Piece>(body, rollout);
  const Piece r(body, rollout);
  const int D = body.num_modes(), nz = StateTangentSize(body), N = rollout.steps();
  const BodyState<Dim, double> start = r.Start();
  const int interval = CheckpointInterval(N, checkpoint_interval, Piece::StepBytes(start));
  RolloutGradient g;
  g.stiffness = Eigen::VectorXd::Zero(D);
  g.damping = Eigen::VectorXd::Zero(D);
  g.targets = Eigen::MatrixXd::Zero(D, N);
  Eigen::VectorXd dz(nz);
  auto stage = [&](int n, const BodyState<Dim, double>& s, StateAdjoint<Dim>* lambda) {
    dz.setZero();
    g.cost += cost(n, s, &dz);
    lambda->z += dz;
  };
  auto step = [&](int n, BodyState<Dim, double>* s) { return r.Advance(n, s, &g.message); };
  // A taped piece's recompute of an interval keeps each step's tape (slot n mod interval;
  // `taped` says which step a slot holds), so the product does not evaluate the step a third
  // time: about one simulation less per gradient (the interval's last step has none and is
  // taken again, except when the interval is the whole run, whose forward run keeps every tape).
  using Tape = typename Piece::Tape;
  using Buffers = SweepBuffers<BodyState<Dim, double>, Tape>;
  thread_local Buffers kept;
  Buffers own;
  Buffers& buffers = kept.in_use ? own : kept;
  buffers.in_use = true;
  struct ReleaseAtExit {
    Buffers* b;
    ~ReleaseAtExit() { b->Release(); }
  } release_at_exit{&buffers};
  std::vector<Tape>& tapes = buffers.tapes;
  // a slot is read only after Record wrote it in this gradient (`taped`), so old contents are harmless
  tapes.resize(Piece::kTaped ? size_t(std::min(interval, std::max(N, 1))) : 0);
  std::vector<int> taped(tapes.size(), -1);
  auto recompute = [&](int n, BodyState<Dim, double>* s) {
    if constexpr (Piece::kTaped) {
      const size_t slot = size_t(n % int(tapes.size()));
      taped[slot] = n;
      return r.Record(n, s, &tapes[slot], &g.message);
    } else {
      return r.Advance(n, s, &g.message);
    }
  };
  auto vjp = [&](int n, const BodyState<Dim, double>& state, const BodyState<Dim, double>& next,
                 const StateAdjoint<Dim>& out, StateAdjoint<Dim>* in) {
    const Tape* tape = nullptr;
    if constexpr (Piece::kTaped) {
      const size_t slot = size_t(n % int(tapes.size()));
      if (taped[slot] == n) tape = &tapes[slot];
    }
    return r.Vjp(n, state, next, tape, out, in, &g, &g.message);
  };
  StateAdjoint<Dim> lambda{Eigen::VectorXd::Zero(nz), {}};
  if (!CheckpointedAdjointSweep(N, interval, start, &lambda, step, recompute, vjp, stage, &g.states_held,
                                &buffers.checkpoints, &buffers.segment))
    return g;
  g.start = lambda.z;
  r.StartVjp(lambda, &g.start);
  if (!std::isfinite(g.cost)) {
    g.message = "the cost is not finite";
    return g;
  }
  g.ok = true;
  return g;
}

}  // namespace wobble::fit::internal
