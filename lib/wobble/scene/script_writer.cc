#include "wobble/scene/script_writer.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "wobble/formats/csv.h"

namespace wobble::scene {
namespace {

// Shortest round-trip form: the replay reads back the same doubles.
std::string Num(double v) { return formats::FormatDouble(v); }

void Vector(std::ostream& s, const char* name, const Eigen::VectorXd& v) {
  s << "set_vec " << name;
  for (int i = 0; i < v.size(); ++i) s << " " << Num(v[i]);
  s << "\n";
}

// A session's setup: its body's modes, all active, with the damping they had (codamA 0).
ScriptSetup SessionSetup(const SessionRecord& r) {
  if (!r.body) throw std::invalid_argument("SessionScript: no body");
  if (r.object_path.empty()) throw std::invalid_argument("SessionScript: the object file is not known");
  ScriptSetup setup;
  setup.object_path = r.object_path;
  setup.mode_paths = r.mode_paths;
  setup.modes = ModeSettings(r.body->modes());
  for (ModeSetting& m : setup.modes) m.active = true;
  setup.world = r.world;
  setup.springs = r.world.params.springs;
  setup.q = r.q0;
  setup.qd = r.qd0;
  return setup;
}

}  // namespace

void WriteSetup(std::ostream& s, const ScriptSetup& r) {
  const Ground& g = r.world.params.ground;
  s << "load_obj " << r.object_path << "\n";
  if (!r.mode_paths.empty()) {
    s << "load_def";
    for (const std::string& p : r.mode_paths) s << " " << p;
    s << "\n";
  }
  s << "set codamA " << Num(r.codam_active) << "\n";
  for (size_t d = 0; d < r.modes.size(); ++d) {
    s << "assign " << d + 1 << " " << Num(r.modes[d].stiffness) << " " << Num(r.modes[d].damping) << "\n";
    s << "mode " << d + 1 << (r.modes[d].active ? " active" : " passive") << "\n";
  }
  s << "set gravity " << (r.world.params.gravity_on ? "T" : "F") << "\nset g " << Num(-r.world.params.gravity.y())
    << "\n";
  s << "set ground " << (g.enabled ? "T" : "F") << "\n";
  s << "set grconst " << Num(g.stiffness) << "\nset grdam " << Num(g.normal_damping) << "\nset frconst "
    << Num(g.friction_damping) << "\nset frsin " << Num(g.friction_cap) << "\n";
  // the script's ground passes through (0, ground_height)
  s << "set ground_height " << Num(g.point.y() - std::tan(g.slope) * g.point.x()) << "\n";
  s << "set ground_slope " << Num(g.slope * 180.0 / M_PI) << "\n";
  s << "set max_penetration " << Num(g.max_penetration) << "\n";
  s << "terrain off\n";
  if (g.terrain) {
    s << "terrain";
    for (const Eigen::Vector2d& v : g.terrain->vertices()) s << " " << Num(v.x()) << " " << Num(v.y());
    s << "\n";
    const std::vector<SurfaceOverrides>& faces = g.terrain->segments();
    for (size_t i = 0; i < faces.size(); ++i) {
      const std::pair<const char*, double> own[] = {{"grconst", faces[i].stiffness},
                                                    {"grdam", faces[i].normal_damping},
                                                    {"frconst", faces[i].friction_damping},
                                                    {"frsin", faces[i].friction_cap}};
      std::string line;
      for (const auto& [name, value] : own)
        if (!std::isnan(value)) line += std::string(" ") + name + " " + Num(value);
      if (!line.empty()) s << "terrain_face " << i + 1 << line << "\n";
    }
  }
  s << "heightfield off\n";
  if (!r.heightfield_path.empty()) s << "heightfield " << r.heightfield_path << "\n";
  else if (r.world.params.ground.heightfield) s << "# the heightfield is kept by `save FILE` only (beside FILE)\n";
  s << "set integrator " << IntegratorName(r.world.integrator) << "\nset dt " << Num(r.world.dt) << "\n";
  s << "set spring " << (r.springs_on ? "T" : "F") << "\nclear springs\n";
  for (const Spring& sp : r.springs) {
    s << "spring";
    for (int a = 0; a < r.dim; ++a) s << " " << Num(sp.lattice_coords[a]);
    for (int a = 0; a < r.dim; ++a) s << " " << Num(sp.anchor[a]);
    s << " " << Num(sp.stiffness) << " " << Num(sp.damping) << " " << Num(sp.rest_length) << "\n";
  }
  s << "trans 0 0 0\n";
  Vector(s, "q", r.q);
  Vector(s, "dq", r.qd);
  s << "clear poses\n";
}

void WritePoseGraph(std::ostream& s, const control::PoseGraph& graph, double switch_width) {
  s << "set cyclic " << (graph.cyclic ? "T" : "F") << "\n";
  s << "set switch_width " << Num(switch_width) << "\n";
  for (size_t i = 0; i < graph.poses.size(); ++i) {
    s << "pose";
    for (int k = 0; k < graph.poses[i].size(); ++k) s << " " << Num(graph.poses[i][k]);
    s << " " << Num(graph.durations[i]) << "\n";
  }
}

std::string ReplayScript(const ScriptSetup& setup, const control::PoseGraph& graph, double switch_width, double t0,
                         double t1, const std::string& schedule) {
  std::ostringstream s;
  s << "# Written by wobble (save): rebuilds the setup and replays its controller with simul.\n";
  WriteSetup(s, setup);
  WritePoseGraph(s, graph, switch_width);
  if (!schedule.empty()) s << "schedule " << schedule << "\n";
  s << "set time " << Num(t0) << "\nset end " << Num(t1) << "\n";
  s << "# output replay.csv   # uncomment to record the motion\n";
  s << "simul\nprint\n";
  return s.str();
}

std::string SessionScript(const SessionRecord& r) {
  const ScriptSetup setup = SessionSetup(r);
  const double dt = r.world.dt;
  const int D = r.body->num_modes();
  // one pose per target change; boundaries half a step before the change (see the header)
  control::PoseGraph graph;
  graph.cyclic = false;
  bool any = false;
  for (size_t i = 0; i < r.segments.size(); ++i) {
    const SessionRecord::Segment& seg = r.segments[i];
    if (seg.targets.size() != D) throw std::invalid_argument("SessionScript: a segment has the wrong number of targets");
    if (i > 0 && seg.step <= r.segments[i - 1].step) throw std::invalid_argument("SessionScript: segments out of order");
    any = any || !seg.targets.isZero(0.0);
    double duration;
    if (i + 1 < r.segments.size()) {
      const long to = r.segments[i + 1].step;
      duration = i == 0 ? (double(to) - 0.5) * dt : double(to - seg.step) * dt;
    } else {
      duration = double(std::max(1L, r.steps - r.key_steps - seg.step + 1)) * dt;  // the last pose is held after the end
    }
    graph.poses.push_back(seg.targets);
    graph.durations.push_back(duration);
  }
  if (D == 0 || !any) graph = {};  // the targets stay zero: no pose graph
  std::ostringstream s;
  s << "# Written by wobble view: the session from t = " << Num(r.t0) << " for " << r.steps << " steps of " << Num(dt)
    << " s.\n# `wobble run THIS_FILE` replays it: the same start, the same PD targets at the same steps.\n";
  if (r.drags > 0)
    s << "# The session had " << r.drags << " pull(s) by the mouse (a spring to the cursor), from step "
      << r.first_drag_step << " on: the language has no moving spring, so the replay follows the session only "
      << "until then.\n";
  WriteSetup(s, setup);
  s << "set time " << Num(r.t0) << "\n";
  long simulated = r.steps;
  if (!r.keys.times.empty()) {
    if (r.keys.amplitudes.size() != r.keys.times.size()) throw std::invalid_argument("SessionScript: one amplitude set per key");
    if (r.hold.enabled) {  // `hold S T` or `hold S T U`: as many coordinates as the body has dimensions
      s << "hold";
      for (int a = 0; a < r.body->dim(); ++a) s << " " << Num(r.hold.lattice_coords[a]);
      s << "\n";
    }
    s << "set interp " << (r.keys.interpolation == control::Interpolation::kSmooth ? "smooth" : "linear") << "\n";
    for (size_t k = 0; k < r.keys.times.size(); ++k) {
      if (r.keys.amplitudes[k].size() != D) throw std::invalid_argument("SessionScript: a key has the wrong number of amplitudes");
      s << "key " << Num(r.keys.times[k]);
      for (int d = 0; d < D; ++d) s << " " << d + 1 << "=" << Num(r.keys.amplitudes[k][d]);
      s << "\n";
    }
    s << "keyframe\n";
    simulated = r.steps - r.key_steps;
    if (simulated <= 0) {
      s << "# saved while the keys played (" << r.steps << " of their steps): the replay plays them to their end\n";
      simulated = 0;
    }
  }
  if (simulated > 0) {
    if (!graph.empty()) WritePoseGraph(s, graph, 0.0);
    s << "simul " << Num(double(simulated) * dt) << "\n";
  }
  s << "print\n";
  return s.str();
}

std::string PoseGraphScript(const SessionRecord& r, const std::vector<Eigen::VectorXd>& poses,
                            const std::vector<double>& durations, int cycles) {
  if (poses.empty() || poses.size() != durations.size())
    throw std::invalid_argument("PoseGraphScript: one duration per pose, at least one pose");
  const ScriptSetup setup = SessionSetup(r);
  control::PoseGraph graph;
  for (size_t i = 0; i < poses.size(); ++i) {
    if (poses[i].size() != r.body->num_modes()) throw std::invalid_argument("PoseGraphScript: a pose has the wrong size");
    if (!(durations[i] > 0)) throw std::invalid_argument("PoseGraphScript: durations must be positive");
    graph.poses.push_back(poses[i]);
    graph.durations.push_back(durations[i]);
  }
  std::ostringstream s;
  s << "# Written by wobble view: " << poses.size() << " recorded pose(s) as a cyclic pose graph (chapter 5), "
    << "from the session's start state, simulated for " << cycles << " period(s).\n";
  WriteSetup(s, setup);
  WritePoseGraph(s, graph, 0.0);
  s << "set time " << Num(r.t0) << "\nsimul " << Num(cycles * graph.Period()) << "\nprint\n";
  return s.str();
}

}  // namespace wobble::scene
