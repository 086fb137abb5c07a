#include "wobble/synth/anneal.h"

#include "wobble/control/controllers.h"
#include "wobble/core/interrupt.h"
#include "wobble/core/distribute.h"
#include "wobble/scene/ffd_object.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <random>
#include <sstream>

namespace wobble::synth {

std::string CostKindName(CostKind kind) {
  switch (kind) {
    case CostKind::kInverseDistance: return "inverse_distance";
    case CostKind::kEnergyPerDistance: return "energy_per_distance";
    case CostKind::kEnergyPerSqrtDistanceSpeed: return "energy_per_sqrt_distance_speed";
    case CostKind::kEnergyPerSqrtDistance: return "energy_per_sqrt_distance";
  }
  return "?";
}

bool ParseCostKind(const std::string& text, CostKind* kind) {
  for (CostKind k : {CostKind::kInverseDistance, CostKind::kEnergyPerDistance, CostKind::kEnergyPerSqrtDistanceSpeed,
                     CostKind::kEnergyPerSqrtDistance})
    if (CostKindName(k) == text) {
      *kind = k;
      return true;
    }
  return false;
}

std::string OptimizeName(Optimize what) {
  switch (what) {
    case Optimize::kPoses: return "poses";
    case Optimize::kTimes: return "times";
    case Optimize::kBoth: return "both";
  }
  return "?";
}

bool ParseOptimize(const std::string& text, Optimize* what) {
  for (Optimize o : {Optimize::kPoses, Optimize::kTimes, Optimize::kBoth})
    if (OptimizeName(o) == text) {
      *what = o;
      return true;
    }
  return false;
}

double EvaluateCost(const CostFunction& c, const TrialOutcome& o) {
  // Table 5.1, with the thesis' rule: q_x q̇_x < 0 costs `high` (and so does going backwards,
  // where the square roots and quotients have no meaning)
  if (!o.ok || !(o.distance > 0.0)) return c.high;
  switch (c.kind) {
    case CostKind::kInverseDistance: return 1.0 / o.distance;
    case CostKind::kEnergyPerDistance: return o.energy / o.distance;
    case CostKind::kEnergyPerSqrtDistanceSpeed:
      if (o.distance * o.speed < 0.0) return c.high;
      if (o.speed == 0.0) return c.high;
      return o.energy / (c.scale * std::sqrt(o.distance * o.speed));
    case CostKind::kEnergyPerSqrtDistance: return o.energy / (c.scale * std::sqrt(o.distance));
  }
  return c.high;
}

void CenterOfMassX(const BodyModel& body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double* x, double* v) {
  const MassMoments& mm = body.moments();
  const int D = body.num_modes();
  const Eigen::Vector2d l = mm.c0 + mm.C * q.tail(D);
  const Eigen::Matrix2d R = Rotation(q[2]);
  const Eigen::Vector2d pos = q.head<2>() + R * l / mm.m;
  const Eigen::Vector2d vel = qd.head<2>() + (R * Perp<double>(l) * qd[2] + R * (mm.C * qd.tail(D))) / mm.m;
  *x = pos.x();
  *v = vel.x();
}

void CenterOfMassX(const World& world, double* x, double* v) {
  if (world.IsFfd(0, 2)) return CenterOfMassX(world.body<2>(0), world.q(0), world.qd(0), x, v);
  const MassMomentsN<3>& mm = world.body<3>(0).moments();
  const BodyState<3, double>& s = world.state<3>(0);
  const int D = int(s.gamma().size());
  const Eigen::Vector3d l = (mm.c0 + mm.C * s.gamma()) / mm.m;
  const Eigen::Vector3d vel = s.qd.head<3>() + s.orientation() * (s.qd.segment<3>(3).cross(l) + mm.C * s.qd.tail(D) / mm.m);
  *x = (s.translation() + s.orientation() * l).x();
  *v = vel.x();
}

TrialOutcome RunTrial(const Problem& p, const control::PoseGraph& graph,
                      const std::function<void(const World&)>& on_step) {
  if (p.custom_cost) {
    TrialOutcome out;
    out.cost = p.custom_cost(graph);
    out.ok = std::isfinite(out.cost);
    if (!out.ok) out.cost = p.cost.high;
    return out;
  }
  return TrialWorld(p).Run(graph, on_step);
}

TrialWorld::TrialWorld(const Problem& p) : problem_(p), world_(p.world) {
  if (p.custom_cost) return;  // Run asks the cost
  if (p.dim() == 3) {
    world_.AddBody(p.body<3>());
    world_.SetCoordinates(0, p.q0, p.qd0);
  } else {
    world_.AddBody(p.body<2>());
    world_.SetState(0, p.q0, p.qd0);
  }
  start_ = world_.data();
}

TrialOutcome TrialWorld::Run(const control::PoseGraph& graph, const std::function<void(const World&)>& on_step) {
  const Problem& p = problem_;
  if (p.custom_cost) return RunTrial(p, graph, on_step);
  TrialOutcome out;
  World& world = world_;
  world.SetData(start_);  // the start state, clock and status: nothing of the last trial stays
  world.ClearControllers();
  double x0, v0;
  CenterOfMassX(world, &x0, &v0);
  if (!graph.empty()) {  // the pose graph picks the targets of every step (chapter 5)
    try {
      world.AddController(std::make_shared<control::PoseGraphController>(world, 0, graph));
    } catch (const std::invalid_argument& e) {
      out.failure = e.what();
      out.cost = p.cost.high;
      return out;
    }
  }
  const double dt = p.world.dt;
  control::ControlEnergy energy;
  for (long n = 0; n < p.steps; ++n) {
    if (!world.Step()) {
      out.failure = world.status().message;
      out.cost = p.cost.high;
      return out;
    }
    if (p.dim() == 3) energy.Accumulate(*p.body<3>(), world.state<3>(0), dt);
    else energy.Accumulate(*p.body<2>(), world.state<2>(0), dt);
    if (on_step) on_step(world);
  }
  out.ok = true;
  double x1, v1;
  CenterOfMassX(world, &x1, &v1);
  out.distance = x1 - x0;
  out.speed = v1;
  out.energy = energy.consumed;
  out.cost = EvaluateCost(p.cost, out);
  return out;
}

Bytes EncodeTrialOutcome(const TrialOutcome& o) {
  return ByteWriter()
      .Put<std::uint8_t>(o.ok)
      .Put(o.distance)
      .Put(o.speed)
      .Put(o.energy)
      .Put(o.cost)
      .PutString(o.failure)
      .Take();
}

TrialOutcome DecodeTrialOutcome(const Bytes& bytes) {
  ByteReader in(bytes);
  TrialOutcome o;
  o.ok = in.Get<std::uint8_t>() != 0;
  o.distance = in.Get<double>();
  o.speed = in.Get<double>();
  o.energy = in.Get<double>();
  o.cost = in.Get<double>();
  o.failure = in.GetString();
  return o;
}

std::vector<TrialOutcome> RunTrials(const Problem& p, const std::vector<control::PoseGraph>& graphs, int threads) {
  MapOptions options;
  options.threads = threads;
  // the worlds of the workers: one per trial running at a time, made at first need and handed
  // back after each trial (TrialWorld resets its data, so which one runs a trial does not matter)
  std::mutex mutex;
  std::vector<std::unique_ptr<TrialWorld>> idle;
  const std::vector<Bytes> results = DistributedMap(graphs.size(), options, [&](size_t i) {
    TrialOutcome out;
    if (InterruptRequested()) {  // Ctrl-C: the trials not yet started are not run
      out.failure = kInterruptedTrial;
      out.cost = p.cost.high;
      return EncodeTrialOutcome(out);
    }
    std::unique_ptr<TrialWorld> world;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!idle.empty()) {
        world = std::move(idle.back());
        idle.pop_back();
      }
    }
    if (!world) world = std::make_unique<TrialWorld>(p);
    out = world->Run(graphs[i]);
    std::lock_guard<std::mutex> lock(mutex);
    idle.push_back(std::move(world));
    return EncodeTrialOutcome(out);
  });
  std::vector<TrialOutcome> out;
  out.reserve(results.size());
  for (const Bytes& b : results) out.push_back(DecodeTrialOutcome(b));
  return out;
}

std::string AnnealOptions::Validate() const {
  std::ostringstream err;
  if (iterations < 0) return "iterations must be at least 0";
  if (batch < 1) return "batch must be at least 1";
  if (!(cooling > 0.0 && cooling <= 1.0)) return "cooling must be in (0, 1]";
  if (!(initial_temperature >= 0.0) || !std::isfinite(initial_temperature)) return "temperature must be >= 0";
  if (!(pose_step >= 0.0) || !(time_step >= 0.0)) return "step sizes must be >= 0";
  if (!(min_amplitude < max_amplitude)) return "amplitude bounds must satisfy min < max";
  if (!(min_time > 0.0 && min_time < max_time)) return "time bounds must satisfy 0 < min < max";
  return "";
}

namespace {

// A random neighbour of P (Fig. 5.2 step 4a): every target moves by N(0, pose_step) and every
// transition time is scaled by exp(N(0, time_step)), within the bounds.
control::PoseGraph Neighbour(const control::PoseGraph& p, const AnnealOptions& o, std::mt19937_64* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  control::PoseGraph n = p;
  if (o.optimize != Optimize::kTimes)
    for (Eigen::VectorXd& pose : n.poses)
      for (int i = 0; i < pose.size(); ++i)
        pose[i] = std::clamp(pose[i] + o.pose_step * normal(*rng), o.min_amplitude, o.max_amplitude);
  if (o.optimize != Optimize::kPoses)
    for (double& d : n.durations) d = std::clamp(d * std::exp(o.time_step * normal(*rng)), o.min_time, o.max_time);
  return n;
}

}  // namespace

AnnealResult Anneal(const Problem& p, const control::PoseGraph& initial, const AnnealOptions& o,
                    const std::function<void(const IterationRecord&)>& on_iteration) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  AnnealResult r;
  // steps 1-3: the initial controller, its cost and the starting temperature
  control::PoseGraph current = initial;
  TrialOutcome current_outcome = RunTrial(p, current);
  r.initial_outcome = r.best_outcome = current_outcome;
  r.best = current;
  r.trials = 1;
  double T = o.initial_temperature > 0.0 ? o.initial_temperature
                                         : (current_outcome.cost < p.cost.high ? 0.1 * current_outcome.cost : 1.0);
  auto record = [&](const IterationRecord& rec) {
    r.history.push_back(rec);
    if (on_iteration) on_iteration(rec);
  };
  record({0, r.trials, current_outcome.cost, current_outcome.cost, current_outcome.cost, T, true});
  // step 4: neighbours, acceptance, cooling
  for (int it = 1; it <= o.iterations; ++it) {
    if (InterruptRequested()) {  // between two batches: what is best so far is a result
      r.interrupted = true;
      break;
    }
    std::vector<control::PoseGraph> candidates;
    for (int b = 0; b < o.batch; ++b) candidates.push_back(Neighbour(current, o, &rng));
    const std::vector<TrialOutcome> outcomes = RunTrials(p, candidates, o.threads);
    r.trials += long(candidates.size());
    int pick = 0;
    for (int b = 1; b < o.batch; ++b)
      if (outcomes[b].cost < outcomes[pick].cost) pick = b;
    const double delta = outcomes[pick].cost - current_outcome.cost;
    // the uniform draw is made every iteration so that the stream never depends on Δ's sign
    const double u = uniform(rng);
    const bool accept = delta <= 0.0 || u < std::exp(-delta / T);
    if (accept) {
      current = candidates[pick];
      current_outcome = outcomes[pick];
    }
    if (outcomes[pick].cost < r.best_outcome.cost) {
      r.best = candidates[pick];
      r.best_outcome = outcomes[pick];
    }
    record({it, r.trials, outcomes[pick].cost, current_outcome.cost, r.best_outcome.cost, T, accept});
    T *= o.cooling;
  }
  return r;
}

std::vector<std::string> HistoryHeader() {
  return {"iteration", "trials", "candidate_cost", "current_cost", "best_cost", "temperature", "accepted"};
}

std::vector<std::vector<double>> HistoryRows(const std::vector<IterationRecord>& history) {
  std::vector<std::vector<double>> rows;
  for (const IterationRecord& h : history)
    rows.push_back({double(h.iteration), double(h.trials), h.candidate, h.current, h.best, h.temperature,
                    h.accepted ? 1.0 : 0.0});
  return rows;
}

std::vector<double> DistancePerCycle(const Problem& problem, const control::PoseGraph& graph, int skip, int cycles) {
  Problem p = problem;
  const double period = graph.Period();
  const double dt = p.world.dt;
  p.steps = long(std::ceil((skip + cycles) * period / dt)) + 1;
  std::vector<double> marks;  // tx at every cycle boundary from `skip` on
  int next_cycle = skip;
  RunTrial(p, graph, [&](const World& w) {
    if (next_cycle <= skip + cycles && w.time() + 0.5 * dt >= next_cycle * period) {
      double x, v;
      CenterOfMassX(w, &x, &v);
      marks.push_back(x);
      ++next_cycle;
    }
  });
  std::vector<double> out;
  for (size_t i = 1; i < marks.size(); ++i) out.push_back(marks[i] - marks[i - 1]);
  return out;
}

std::string EncodeAnnealResult(const AnnealResult& r) {
  ByteWriter w;
  w.Put<std::uint8_t>(r.best.cyclic).Put<std::uint64_t>(r.best.poses.size());
  for (const Eigen::VectorXd& p : r.best.poses) w.PutDoubles(std::vector<double>(p.data(), p.data() + p.size()));
  w.PutDoubles(r.best.durations);
  w.PutString(EncodeTrialOutcome(r.best_outcome)).PutString(EncodeTrialOutcome(r.initial_outcome));
  w.Put<std::uint64_t>(r.history.size());
  for (const IterationRecord& h : r.history)
    w.Put<std::int32_t>(h.iteration).Put<std::int64_t>(h.trials).Put(h.candidate).Put(h.current).Put(h.best)
        .Put(h.temperature).Put<std::uint8_t>(h.accepted);
  w.Put<std::int64_t>(r.trials).Put<std::uint8_t>(r.interrupted);
  return w.Take();
}

AnnealResult DecodeAnnealResult(const std::string& bytes) {
  ByteReader in(bytes);
  AnnealResult r;
  r.best.cyclic = in.Get<std::uint8_t>() != 0;
  r.best.poses.resize(in.Get<std::uint64_t>());
  for (Eigen::VectorXd& p : r.best.poses) {
    const std::vector<double> v = in.GetDoubles();
    p = Eigen::Map<const Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
  }
  r.best.durations = in.GetDoubles();
  r.best_outcome = DecodeTrialOutcome(in.GetString());
  r.initial_outcome = DecodeTrialOutcome(in.GetString());
  r.history.resize(in.Get<std::uint64_t>());
  for (IterationRecord& h : r.history) {
    h.iteration = in.Get<std::int32_t>();
    h.trials = long(in.Get<std::int64_t>());
    h.candidate = in.Get<double>();
    h.current = in.Get<double>();
    h.best = in.Get<double>();
    h.temperature = in.Get<double>();
    h.accepted = in.Get<std::uint8_t>() != 0;
  }
  r.trials = long(in.Get<std::int64_t>());
  r.interrupted = in.Get<std::uint8_t>() != 0;
  return r;
}

AnnealResult BestOfRestarts(int restarts, const std::function<AnnealResult(int restart)>& run) {
  if (restarts < 1) throw std::invalid_argument("restarts must be at least 1");
  const std::vector<Bytes> results = DistributedMap(size_t(restarts), MapOptions(), [&](size_t k) {
    return EncodeAnnealResult(run(int(k)));
  });
  AnnealResult best = DecodeAnnealResult(results[0]);
  long trials = best.trials;
  bool interrupted = best.interrupted;
  for (size_t k = 1; k < results.size(); ++k) {
    AnnealResult r = DecodeAnnealResult(results[k]);
    trials += r.trials;
    interrupted = interrupted || r.interrupted;
    if (r.best_outcome.cost < best.best_outcome.cost) best = std::move(r);
  }
  best.trials = trials;
  best.interrupted = interrupted;
  return best;
}

}  // namespace wobble::synth
