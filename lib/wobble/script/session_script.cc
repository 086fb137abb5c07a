#include "wobble/script/session_script.h"

#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace wobble::script {
namespace {

std::string Num(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

void Vector(std::ostream& s, const char* name, const Eigen::VectorXd& v) {
  s << "set_vec " << name;
  for (int i = 0; i < v.size(); ++i) s << " " << Num(v[i]);
  s << "\n";
}

// Object, modes (all active, K and c as the body has them), world parameters, springs, state.
void Setup(std::ostream& s, const SessionRecord& r) {
  if (!r.body) throw std::invalid_argument("SessionScript: no body");
  if (r.object_path.empty()) throw std::invalid_argument("SessionScript: the object file is not known");
  const Ground& g = r.world.params.ground;
  s << "load_obj " << r.object_path << "\n";
  if (!r.mode_paths.empty()) {
    s << "load_def";
    for (const std::string& p : r.mode_paths) s << " " << p;
    s << "\n";
  }
  s << "set codamA 0\n";
  for (int d = 0; d < r.body->num_modes(); ++d) {
    const DeformationMode& m = r.body->modes()[d];
    s << "assign " << d + 1 << " " << Num(m.stiffness) << " " << Num(m.damping) << "\n";
    s << "mode " << d + 1 << " active\n";
  }
  s << "set gravity " << (r.world.params.gravity_on ? "T" : "F") << "\n";
  s << "set ground " << (g.enabled ? "T" : "F") << "\n";
  s << "set grconst " << Num(g.stiffness) << "\nset grdam " << Num(g.normal_damping) << "\nset frconst "
    << Num(g.friction_damping) << "\nset frsin " << Num(g.friction_cap) << "\n";
  // the script's ground passes through (0, ground_height)
  s << "set ground_height " << Num(g.point.y() - std::tan(g.slope) * g.point.x()) << "\n";
  s << "set ground_slope " << Num(g.slope * 180.0 / M_PI) << "\n";
  s << "set max_penetration " << Num(g.max_penetration) << "\n";
  s << "set integrator " << IntegratorName(r.world.integrator) << "\nset dt " << Num(r.world.dt) << "\n";
  s << "set spring T\nclear springs\n";
  for (const Spring& sp : r.world.params.springs)
    s << "spring " << Num(sp.lattice_coords.x()) << " " << Num(sp.lattice_coords.y()) << " " << Num(sp.anchor.x()) << " "
      << Num(sp.anchor.y()) << " " << Num(sp.stiffness) << " " << Num(sp.damping) << " " << Num(sp.rest_length) << "\n";
  s << "trans 0 0 0\n";
  Vector(s, "q", r.q0);
  Vector(s, "dq", r.qd0);
  s << "clear poses\n";
}

}  // namespace

std::string SessionScript(const SessionRecord& r) {
  std::ostringstream s;
  const double dt = r.world.dt;
  s << "# Written by wobble view: the session from t = " << Num(r.t0) << " for " << r.steps << " steps of " << Num(dt)
    << " s.\n# `wobble run THIS_FILE` replays it: the same start, the same PD targets at the same steps.\n";
  if (r.drags > 0)
    s << "# The session had " << r.drags << " pull(s) by the mouse (a spring to the cursor), from step "
      << r.first_drag_step << " on: the language has no moving spring, so the replay follows the session only "
      << "until then.\n";
  Setup(s, r);
  const int D = r.body->num_modes();
  // one pose per target change; boundaries half a step before the change (see the header)
  bool any = false;
  for (const SessionRecord::Segment& seg : r.segments)
    if (seg.targets.size() != D) throw std::invalid_argument("SessionScript: a segment has the wrong number of targets");
    else if (!seg.targets.isZero(0.0)) any = true;
  if (D > 0 && any) {
    s << "set cyclic F\n";
    for (size_t i = 0; i < r.segments.size(); ++i) {
      const long from = r.segments[i].step;
      if (i > 0 && from <= r.segments[i - 1].step) throw std::invalid_argument("SessionScript: segments out of order");
      double duration;
      if (i + 1 < r.segments.size()) {
        const long to = r.segments[i + 1].step;
        duration = i == 0 ? (double(to) - 0.5) * dt : double(to - from) * dt;
      } else {
        duration = double(std::max(1L, r.steps - from + 1)) * dt;  // the last pose is held after the end
      }
      s << "pose";
      for (int d = 0; d < D; ++d) s << " " << Num(r.segments[i].targets[d]);
      s << " " << Num(duration) << "\n";
    }
  }
  s << "set time " << Num(r.t0) << "\n";
  s << "simul " << Num(double(r.steps) * dt) << "\n";
  s << "print\n";
  return s.str();
}

std::string PoseGraphScript(const SessionRecord& r, const std::vector<Eigen::VectorXd>& poses,
                            const std::vector<double>& durations, int cycles) {
  if (poses.empty() || poses.size() != durations.size())
    throw std::invalid_argument("PoseGraphScript: one duration per pose, at least one pose");
  std::ostringstream s;
  s << "# Written by wobble view: " << poses.size() << " recorded pose(s) as a cyclic pose graph (chapter 5), "
    << "from the session's start state, simulated for " << cycles << " period(s).\n";
  Setup(s, r);
  double period = 0.0;
  s << "set cyclic T\n";
  for (size_t i = 0; i < poses.size(); ++i) {
    if (poses[i].size() != r.body->num_modes()) throw std::invalid_argument("PoseGraphScript: a pose has the wrong size");
    if (!(durations[i] > 0)) throw std::invalid_argument("PoseGraphScript: durations must be positive");
    s << "pose";
    for (int d = 0; d < poses[i].size(); ++d) s << " " << Num(poses[i][d]);
    s << " " << Num(durations[i]) << "\n";
    period += durations[i];
  }
  s << "set time " << Num(r.t0) << "\nsimul " << Num(cycles * period) << "\nprint\n";
  return s.str();
}

}  // namespace wobble::script
