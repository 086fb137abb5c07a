// The World's integrators with constraints on: the multiplier solve (world_constraints.cc) is
// a stage that every integrator evaluates wherever it evaluates accelerations (world.h).
#include "wobble/world/world.h"

#include "wobble/dynamics/step.h"

namespace wobble {

namespace {
// A linear body's flattened coordinates are R row by row: index i·n + s holds R_is (§3.3).
using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
}  // namespace

// Every body together through the multipliers with the world's integrator (world.h). The
// variational integrator's discrete Lagrangian has no constraint forces: refused by name.
bool World::StepConstrained() {
  switch (options_.integrator) {
    case Integrator::kThesis: return StepConstrainedThesis();
    case Integrator::kSymplecticEuler:
    case Integrator::kRK4:
    case Integrator::kImplicitEuler: return StepConstrainedStaged();
    case Integrator::kVariational: break;
  }
  return Fail(StatusCode::kUnsupported, -1,
              "the " + IntegratorName(options_.integrator) + " integrator does not take constraints (nails, attachments, "
              "trajectories, behaviours); use thesis, symplectic, rk4 or implicit");
}

// Velocity-first Euler, the Störmer form of Eq. 4.22/4.23: the constrained q̈ at the step's
// start, with the velocities half a step behind the positions.
bool World::StepConstrainedThesis() {
  if (!ConstrainedAccelerations(data_.time, 0.5 * options_.dt, ContactSet::kDetect, &acc_)) return false;
  std::vector<Eigen::VectorXd>& acc = acc_;
  // the whole step is refused when anything is non-finite (ConstrainedAccelerations checked)
  for (int body = 0; body < num_bodies(); ++body) {
    const Slot& b = slots_[body];
    if (b.kinematic) continue;
    if (b.kind == BodyKind::kLinear) {
      if (!StepLinearBody(body, acc[body])) return false;
    } else if (!(b.dim == 3 ? FfdAcceptConstrainedStep<3>(body, acc[body])
                            : FfdAcceptConstrainedStep<2>(body, acc[body]))) {
      return false;
    }
  }
  return true;
}

// ---------------------------------------------------------------- staged integrators

void World::SaveStart(StepStart* start) const {
  start->q.resize(num_bodies());
  start->v.resize(num_bodies());
  for (int body = 0; body < num_bodies(); ++body) {
    const Slot& b = slots_[body];
    if (b.kind == BodyKind::kLinear) {
      const WorldData::Linear& x = data_.linear[size_t(b.index)];
      const int d = int(x.R.rows()), n = int(x.R.cols());
      start->q[body].resize(d * n);
      start->v[body].resize(d * n);
      Eigen::Map<RowMajorMatrix>(start->q[body].data(), d, n) = x.R;  // R row by row, as in acc
      Eigen::Map<RowMajorMatrix>(start->v[body].data(), d, n) = x.R_dot;
    } else if (b.dim == 3) {
      start->q[body] = data_.ffd_of<3>()[size_t(b.index)].state.q;
      start->v[body] = data_.ffd_of<3>()[size_t(b.index)].state.qd;
    } else {
      start->q[body] = data_.ffd_of<2>()[size_t(b.index)].state.q;
      start->v[body] = data_.ffd_of<2>()[size_t(b.index)].state.qd;
    }
  }
}

void World::MoveToStage(int body, const StepStart& start, const Eigen::VectorXd& dy, const Eigen::VectorXd& dv) {
  const Slot& b = slots_[body];
  if (b.kind == BodyKind::kLinear) {
    WorldData::Linear& x = data_.linear[size_t(b.index)];
    const int d = int(x.R.rows()), n = int(x.R.cols());
    x.R = Eigen::Map<const RowMajorMatrix>(start.q[body].data(), d, n) + Eigen::Map<const RowMajorMatrix>(dy.data(), d, n);
    x.R_dot =
        Eigen::Map<const RowMajorMatrix>(start.v[body].data(), d, n) + Eigen::Map<const RowMajorMatrix>(dv.data(), d, n);
  } else if (b.dim == 3) {
    FfdMoveToStage<3>(body, start.q[body], start.v[body], dy, dv);
  } else {
    FfdMoveToStage<2>(body, start.q[body], start.v[body], dy, dv);
  }
}

void World::RestoreStart(const StepStart& start) {
  for (int body = 0; body < num_bodies(); ++body) {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(start.v[body].size());
    MoveToStage(body, start, zero, zero);
  }
}

Eigen::VectorXd World::StageRate(int body, const Eigen::VectorXd& dy, const Eigen::VectorXd& v) const {
  const Slot& b = slots_[body];
  if (b.kind == BodyKind::kLinear || b.dim == 2) return v;  // a vector space; SO(2)'s dexp⁻¹ is 1
  return Group<3>::StageRate(VecQ<double>(dy), VecQ<double>(v));
}

bool World::AcceptStagedState(int body, const StepStart& start) {
  const Slot& b = slots_[body];
  if (b.kind == BodyKind::kLinear) {
    const int d = int(data_.linear[size_t(b.index)].R.rows()), n = int(data_.linear[size_t(b.index)].R.cols());
    return AcceptLinearState(body, Eigen::Map<const RowMajorMatrix>(start.q[body].data(), d, n),
                             Eigen::Map<const RowMajorMatrix>(start.v[body].data(), d, n));
  }
  if (b.dim == 3) return FfdAcceptState<3>(body, start.q[body], start.v[body]);
  return FfdAcceptState<2>(body, start.q[body], start.v[body]);
}

// The integrators of step.h over the whole world, every stage at the constrained q̈ of its own
// state and time (c̈ = −α c − β ċ holds at each; no stagger: lag 0):
//   symplectic  q' = q·exp(Δt v), v' = v + Δt a(q', v) at t + Δt (v lags q' by ½Δt there)
//   rk4         Runge–Kutta–Munthe-Kaas, the classical tableau on the tangent coordinates
//   implicit    v' = v + Δt a(q·exp(Δt v'), v') by Newton, contacts frozen, with an active set
// Kinematic bodies keep their state through every stage. `linear_only`: no constraint is on, and
// only the linear bodies step here, on their free q̈ (FFD bodies take StepBody). λ of the step: the tableau's weighted
// mean of the stages' (rk4), the end's (implicit), the one evaluated (symplectic).
bool World::StepConstrainedStaged(bool linear_only) {
  const double h = options_.dt, t = data_.time;
  const int nb = num_bodies();
  StepStart start;
  SaveStart(&start);
  auto moving = [&](int body) { return !slots_[body].kinematic && (!linear_only || slots_[body].kind == BodyKind::kLinear); };
  // the q̈ of every moving body at its stage: through the multipliers, or free (no constraint)
  auto accelerations = [&](double t_stage, double lag, ContactSet contacts, std::vector<Eigen::VectorXd>* acc) {
    if (!linear_only) return ConstrainedAccelerations(t_stage, lag, contacts, acc);
    acc->resize(nb);
    for (int body = 0; body < nb; ++body) {
      if (!moving(body)) continue;
      LinearFreeAcceleration(body, &(*acc)[body]);
      if (!(*acc)[body].allFinite()) return Fail(StatusCode::kNonFinite, body, "non-finite acceleration");
    }
    return true;
  };
  std::vector<Eigen::VectorXd> dy(nb), dv(nb);
  auto move_all = [&] {
    for (int body = 0; body < nb; ++body)
      if (moving(body)) MoveToStage(body, start, dy[body], dv[body]);
  };
  auto fail = [&] {  // the status is set: every body back at its start
    RestoreStart(start);
    return false;
  };
  switch (options_.integrator) {
    case Integrator::kSymplecticEuler: {
      for (int body = 0; body < nb; ++body) {
        dy[body] = h * start.v[body];  // q·exp(Δt v): the Euler step on the group
        dv[body] = Eigen::VectorXd::Zero(start.v[body].size());
      }
      move_all();
      if (!accelerations(t + h, 0.5 * h, ContactSet::kDetect, &acc_)) return fail();
      for (int body = 0; body < nb; ++body) dv[body] = h * acc_[body];
      move_all();
      break;
    }
    case Integrator::kRK4: {
      std::vector<Eigen::VectorXd> rate[4], k[4], lambda[4];
      const double offset[4] = {0.0, 0.5, 0.5, 1.0};
      for (int i = 0; i < 4; ++i) {
        rate[i].resize(nb);
        for (int body = 0; body < nb; ++body) {
          const int n = int(start.v[body].size());
          dy[body] = i == 0 ? Eigen::VectorXd::Zero(n) : Eigen::VectorXd(offset[i] * h * rate[i - 1][body]);
          dv[body] = i == 0 ? Eigen::VectorXd::Zero(n) : Eigen::VectorXd(offset[i] * h * k[i - 1][body]);
        }
        move_all();
        for (int body = 0; body < nb; ++body)
          rate[i][body] = moving(body) ? StageRate(body, dy[body], start.v[body] + dv[body]) : start.v[body];
        if (!accelerations(t + offset[i] * h, 0.0, ContactSet::kDetect, &k[i])) return fail();
        if (!linear_only) lambda[i] = data_.multipliers;
      }
      for (int body = 0; body < nb; ++body) {
        dy[body] = h / 6.0 * (rate[0][body] + 2.0 * rate[1][body] + 2.0 * rate[2][body] + rate[3][body]);
        dv[body] = h / 6.0 * (k[0][body] + 2.0 * k[1][body] + 2.0 * k[2][body] + k[3][body]);
      }
      for (size_t id = 0; !linear_only && id < data_.multipliers.size(); ++id)
        if (lambda[0][id].size() == data_.multipliers[id].size())
          data_.multipliers[id] = (lambda[0][id] + 2.0 * lambda[1][id] + 2.0 * lambda[2][id] + lambda[3][id]) / 6.0;
      move_all();
      break;
    }
    case Integrator::kImplicitEuler: {
      // the unknown: the end velocities of the moving bodies, stacked
      std::vector<int> offset(nb, 0);
      int size = 0;
      for (int body = 0; body < nb; ++body) {
        offset[body] = size;
        if (moving(body)) size += int(start.v[body].size());
      }
      auto place = [&](const Eigen::VectorXd& v) {  // q·exp(Δt v'), v'
        for (int body = 0; body < nb; ++body) {
          if (!moving(body)) continue;
          const Eigen::VectorXd vb = v.segment(offset[body], start.v[body].size());
          dy[body] = h * vb;
          dv[body] = vb - start.v[body];
        }
        move_all();
      };
      Eigen::VectorXd v(size);
      if (!accelerations(t, 0.0, ContactSet::kDetect, &acc_)) return fail();
      for (int body = 0; body < nb; ++body)  // explicit Euler guess
        if (moving(body)) v.segment(offset[body], start.v[body].size()) = start.v[body] + h * acc_[body];
      StepStatus st;
      for (int pass = 0; pass < 4; ++pass) {
        st = SolveNewton<double>(
            [&](const Eigen::VectorXd& x, Eigen::VectorXd* r) {
              place(x);
              if (!accelerations(t + h, 0.0, ContactSet::kFrozen, &acc_)) return StepStatus{data_.status.code};
              r->resize(size);
              for (int body = 0; body < nb; ++body)
                if (moving(body))
                  r->segment(offset[body], start.v[body].size()) =
                      x.segment(offset[body], start.v[body].size()) - start.v[body] - h * acc_[body];
              return StepStatus{};
            },
            &v);
        if (!st.ok()) break;
        place(v);
        int added = 0;  // points that end the step below the ground join the contacts: again
        for (int body = 0; body < nb; ++body) {
          const Slot& b = slots_[body];
          if (!moving(body) || b.kind != BodyKind::kFfd) continue;
          if (b.dim == 3)
            added += AddMissingContacts(*FfdEntries<3>()[size_t(b.index)].model, GroundFor<3>(),
                                        &data_.ffd_of<3>()[size_t(b.index)].state);
          else
            added += AddMissingContacts(*FfdEntries<2>()[size_t(b.index)].model, GroundFor<2>(),
                                        &data_.ffd_of<2>()[size_t(b.index)].state);
        }
        if (added == 0) break;
      }
      if (!st.ok()) {
        if (data_.status.ok()) Fail(st.code, -1, "the constrained implicit step", st.value);
        return fail();
      }
      // λ of the end state, which the last residual may not have been evaluated at
      if (!linear_only && !accelerations(t + h, 0.0, ContactSet::kFrozen, &acc_)) return fail();
      break;
    }
    case Integrator::kThesis:
    case Integrator::kVariational: break;  // not here (StepConstrained)
  }
  // the new state is in data_: each moving body is checked as every step checks it
  for (int body = 0; body < nb; ++body)
    if (moving(body) && !AcceptStagedState(body, start)) return false;
  return true;
}

}  // namespace wobble
