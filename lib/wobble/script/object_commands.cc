// The commands of the FFD object (thesis §4.10.2, appendix C): loading it, its modes and
// state, its control (pose graphs, keyframes, springs), its runs and what they record
// (`output`, `render`), and the few commands every mode shares (print, echo, help, quit).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "wobble/record/trajectory_csv.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/target_schedule.h"
#include "wobble/scene/render_options.h"
#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

using namespace script_detail;

namespace {

int ModeIndex(const State& s, const std::string& word, const Context& ctx) {
  const int count = s.scene.object().num_modes();
  int index;
  if (formats::detail::ParseInt(word, &index)) {
    if (index < 1 || index > count)
      ctx.Fail("expected a mode number from 1 to " + std::to_string(count) + ", got " + word);
    return index - 1;
  }
  const std::vector<std::string> names = s.scene.object().mode_names();
  const int d = s.scene.object().ModeIndex(word);
  if (d < 0) {
    const std::string near = Interpreter::Nearest(word, names);
    ctx.Fail("no mode '" + word + "' (expected a mode number or one of the loaded names" +
             (near.empty() ? std::string(")") : "; did you mean '" + near + "'?)"));
  }
  return d;
}

// Writes the `output` CSV from every run since `output` (the whole file after every run). The
// path was checked by `output`: a failure now is the disk's (exit 1, not bad input).
void FlushOutput(const State& s, const Context&) {
  if (s.output_path.empty()) return;
  try {
    record::WriteTrajectoryCsv(s.output_path, scene::OutputTrajectory(s.output_runs, s.output_every));
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("output: " + std::string(e.what()));
  }
}

// The run just ended joins what `render` draws and what `output` writes.
void KeepRun(State& s, const Context& ctx) {
  s.track.push_back(s.scene.last_object_run());
  if (!s.output_path.empty()) s.output_runs.push_back(s.scene.last_object_run());
  FlushOutput(s, ctx);
}

}  // namespace

void RequireObject(const State& s, const Context& ctx, const std::string& command) {
  if (!s.scene.object().loaded())
    ctx.Fail(command + " needs an object: 'load_obj FILE' first (or run with --object FILE)");
}


scene::StepCallback StepObserver(State& s, bool object) {
  if (!s.progress && !(object && s.debug)) return nullptr;
  return [&s, object](long n, long steps, const World& world) {
    if (object && s.debug) {
      const Eigen::VectorXd q = world.coordinates(0);
      s.out << "t " << Num(world.time()) << " q";
      for (int i = 0; i < q.size(); ++i) s.out << " " << Num(q[i]);
      s.out << "\n";
    }
    if (s.progress && ((n - 1) % 64 == 0 || n == steps)) s.progress(double(n) / double(steps), world.time());
  };
}

void LoadObj(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  s.scene.object().Load(Resolve(w[1], ctx.dir), s.mesh_reader);
  s.track.clear();
}

void LoadDef(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 64);
  RequireObject(s, ctx, "load_def");
  std::vector<std::string> paths;
  for (size_t i = 1; i < w.size(); ++i) paths.push_back(Resolve(w[i], ctx.dir));
  try {
    s.scene.object().LoadModes(paths);
  } catch (const std::invalid_argument& e) {
    ctx.Fail(std::string("the modes do not fit the object: ") + e.what());
  }
  // poses list the active modes and keys every mode: they no longer fit (§4.10)
  s.scene.control().graph = {};
  s.scene.control().keys = {};
}

void Trans(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 4, 4);
  s.scene.object().SetPlacement({Number(w[1], "X", ctx), Number(w[2], "Y", ctx), Number(w[3], "THETA", ctx)});
}

void Assign(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 4, 4);
  RequireObject(s, ctx, "assign");
  if (s.scene.object().num_modes() == 0) ctx.Fail("assign needs modes: 'load_def FILE' first");
  const int d = ModeIndex(s, w[1], ctx);
  const double k = Number(w[2], "STIFFNESS", ctx), c = Number(w[3], "DAMPING", ctx);
  if (k < 0 || c < 0) ctx.Fail("expected a non-negative stiffness and damping");
  s.scene.object().Assign(d, k, c);
}

void Mode(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 3, 3);
  RequireObject(s, ctx, "mode");
  if (s.scene.object().num_modes() == 0) ctx.Fail("mode needs modes: 'load_def FILE' first");
  const int d = ModeIndex(s, w[1], ctx);
  if (w[2] != "active" && w[2] != "passive") ctx.Fail("expected 'active' or 'passive', got '" + w[2] + "'");
  const bool active = w[2] == "active";
  if (s.scene.object().mode_active(d) != active) s.scene.control().graph = {};  // poses list the active modes
  s.scene.object().SetActive(d, active);
}

void SetVec(State& s, const Words& w, const Context& ctx) {
  RequireObject(s, ctx, "set_vec");
  const int n = s.scene.object().num_q();
  if (w.size() < 2 || (w[1] != "q" && w[1] != "dq")) ctx.Fail("expected 'set_vec q V1 .. Vn' or 'set_vec dq V1 .. Vn'");
  const bool three = s.scene.object().dim() == 3;
  const std::string layout = !three ? "tx ty theta and one per mode"
                             : w[1] == "q" ? "tx ty tz, a rotation vector rx ry rz and one per mode"
                                           : "vx vy vz, the body angular velocity wx wy wz and one per mode";
  if (int(w.size()) - 2 != n)
    ctx.Fail("expected " + std::to_string(n) + " numbers after 'set_vec " + w[1] + "' (" + layout + "), got " +
             std::to_string(w.size() - 2));
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = Number(w[2 + i], "a coordinate", ctx);
  if (w[1] == "q") s.scene.object().SetRelativeQ(v);
  else s.scene.object().SetRelativeQd(v);
}

void Simul(State& s, const Words& w, const Context& ctx) {
  if (s.scene.has_bodies()) return SceneSimul(s, w, ctx);
  ctx.ExpectWords(w, 1, 2);
  RequireObject(s, ctx, "simul");
  double duration = s.scene.end() - s.scene.time();
  if (w.size() == 2) {
    duration = Number(w[1], "DURATION", ctx);
    if (duration < 0) ctx.Fail("expected a non-negative DURATION");
  } else if (duration < 0) {
    ctx.Fail("end (" + Num(s.scene.end()) + ") is before time (" + Num(s.scene.time()) +
             "): set end later, or give a DURATION");
  }
  scene::RunReport r;
  try {
    r = s.scene.Simulate(duration, StepObserver(s, true));
  } catch (const std::invalid_argument& e) {  // the pose graph does not fit the active modes
    ctx.Fail(e.what());
  }
  KeepRun(s, ctx);
  if (!r.ok())
    throw SimulationStopped(ctx.file + ":" + std::to_string(ctx.line) + ": simulation stopped: " + r.status.message);
  const Energies e = s.scene.run_world()->ComputeEnergies(0);
  s.out << "simul: t = " << Num(s.scene.time()) << ", " << r.steps << " steps; kinetic " << Num(e.kinetic) << ", total "
        << Num(e.total()) << ", control energy " << Num(s.scene.control_energy().consumed) << "\n";
}

void Pose(State& s, const Words& w, const Context& ctx) {
  RequireObject(s, ctx, "pose");
  int k = 0;
  for (int d = 0; d < s.scene.object().num_modes(); ++d) k += s.scene.object().mode_active(d) ? 1 : 0;
  if (k == 0) ctx.Fail("pose needs active modes: 'mode MODE active' first");
  if (int(w.size()) != k + 2) ctx.Fail("expected 'pose' with " + std::to_string(k) + " targets (one per active mode) and a DURATION");
  Eigen::VectorXd pose(k);
  for (int i = 0; i < k; ++i) pose[i] = Number(w[1 + i], "a target amplitude", ctx);
  const double duration = Number(w.back(), "DURATION", ctx);
  if (!(duration > 0)) ctx.Fail("expected a positive DURATION, got " + w.back());
  s.scene.control().graph.poses.push_back(pose);
  s.scene.control().graph.durations.push_back(duration);
}

void Key(State& s, const Words& w, const Context& ctx) {
  RequireObject(s, ctx, "key");
  if (w.size() < 2) ctx.Fail("expected '" + ctx.usage + "'");
  control::Keyframes& keys = s.scene.control().keys;
  const double t = Number(w[1], "TIME", ctx);
  if (keys.times.empty() && t != 0.0) ctx.Fail("the first key must be at time 0");
  if (!keys.times.empty() && !(t > keys.times.back())) ctx.Fail("expected a key time after " + Num(keys.times.back()) + ", got " + w[1]);
  const Eigen::VectorXd& q = s.scene.object().q();
  const int D = s.scene.object().num_modes();
  Eigen::VectorXd a = keys.amplitudes.empty() ? Eigen::VectorXd(q.tail(D)) : keys.amplitudes.back();
  for (size_t i = 2; i < w.size(); ++i) {
    const size_t eq = w[i].find('=');
    if (eq == std::string::npos || eq == 0) ctx.Fail("expected MODE=VALUE, got '" + w[i] + "'");
    a[ModeIndex(s, w[i].substr(0, eq), ctx)] = Number(w[i].substr(eq + 1), "an amplitude after '='", ctx);
  }
  keys.times.push_back(t);
  keys.amplitudes.push_back(a);
}

void Hold(State& s, const Words& w, const Context& ctx) {
  control::HeldPoint& hold = s.scene.control().hold;
  if (w.size() == 2 && w[1] == "off") {
    hold.enabled = false;
    return;
  }
  if (s.scene.object().dim() == 3) {  // hold S T U
    if (w.size() != 4) ctx.Fail("expected 'hold S T U' or 'hold off' for a 3D object");
    const Eigen::Vector3d st(Number(w[1], "S", ctx), Number(w[2], "T", ctx), Number(w[3], "U", ctx));
    if (st.minCoeff() < 0 || st.maxCoeff() > 1) ctx.Fail("expected lattice coordinates S, T and U in [0, 1]");
    hold.enabled = true;
    hold.lattice_coords = st;
    return;
  }
  ctx.ExpectWords(w, 3, 3);
  const double u = Number(w[1], "S", ctx), v = Number(w[2], "T", ctx);
  if (u < 0 || u > 1 || v < 0 || v > 1) ctx.Fail("expected lattice coordinates S and T in [0, 1]");
  hold.enabled = true;
  hold.lattice_coords = Eigen::Vector3d(u, v, 0.0);
}

void Keyframe(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 1, 1);
  RequireObject(s, ctx, "keyframe");
  scene::RunReport r;
  try {
    r = s.scene.Keyframe(StepObserver(s, true));
  } catch (const InputError& e) {  // keys asking for an infinite speed, ...
    ctx.Fail(std::string("the keys lead to a state that cannot be: ") + e.what());
  } catch (const std::invalid_argument& e) {
    ctx.Fail(std::string(e.what()) + " ('key TIME MODE=VALUE ...' lines first)");
  }
  KeepRun(s, ctx);
  if (!r.ok())
    throw SimulationStopped(ctx.file + ":" + std::to_string(ctx.line) + ": keyframing stopped: " + r.status.message);
  const Eigen::VectorXd& qd = s.scene.object().qd();
  s.out << "keyframe: t = " << Num(s.scene.time()) << ", " << r.steps << " frames; handed over with dq = [";
  for (int i = 0; i < qd.size(); ++i) s.out << (i ? " " : "") << Num(qd[i]);
  s.out << "]\n";
}

// `spring S T U X Y Z [K C REST]` for a 3D object: the same spring with a third coordinate.
void Spring3Command(State& s, const Words& w, const Context& ctx) {
  if (w.size() < 7 || w.size() > 10) ctx.Fail("expected 'spring S T U X Y Z [K [C [REST]]]' for a 3D object");
  Spring sp;
  sp.lattice_coords = {Number(w[1], "S", ctx), Number(w[2], "T", ctx), Number(w[3], "U", ctx)};
  if (sp.lattice_coords.minCoeff() < 0 || sp.lattice_coords.maxCoeff() > 1)
    ctx.Fail("expected lattice coordinates S, T and U in [0, 1]");
  sp.anchor = {Number(w[4], "X", ctx), Number(w[5], "Y", ctx), Number(w[6], "Z", ctx)};
  sp.stiffness = w.size() > 7 ? Number(w[7], "K", ctx) : s.spring_stiffness;
  sp.damping = w.size() > 8 ? Number(w[8], "C", ctx) : s.spring_damping;
  sp.rest_length = w.size() > 9 ? Number(w[9], "REST", ctx) : 0.0;
  if (sp.stiffness < 0 || sp.damping < 0 || sp.rest_length < 0) ctx.Fail("expected non-negative K, C and REST");
  s.scene.springs().list.push_back(sp);
}

void SpringCommand(State& s, const Words& w, const Context& ctx) {
  RequireObject(s, ctx, "spring");
  if (s.scene.object().dim() == 3) return Spring3Command(s, w, ctx);
  ctx.ExpectWords(w, 5, 8);
  Spring sp;
  sp.lattice_coords = {Number(w[1], "S", ctx), Number(w[2], "T", ctx), 0.0};
  if (sp.lattice_coords.minCoeff() < 0 || sp.lattice_coords.maxCoeff() > 1)
    ctx.Fail("expected lattice coordinates S and T in [0, 1]");
  sp.anchor = {Number(w[3], "X", ctx), Number(w[4], "Y", ctx), 0.0};
  sp.stiffness = w.size() > 5 ? Number(w[5], "K", ctx) : s.spring_stiffness;
  sp.damping = w.size() > 6 ? Number(w[6], "C", ctx) : s.spring_damping;
  sp.rest_length = w.size() > 7 ? Number(w[7], "REST", ctx) : 0.0;
  if (sp.stiffness < 0 || sp.damping < 0 || sp.rest_length < 0) ctx.Fail("expected non-negative K, C and REST");
  s.scene.springs().list.push_back(sp);
}

void Clear(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  if (w[1] == "poses") s.scene.control().graph = {};
  else if (w[1] == "keys") s.scene.control().keys = {};
  else if (w[1] == "springs") s.scene.springs() = {};
  else if (w[1] == "output") s.output_runs.clear();
  else if (w[1] == "energy") s.scene.control_energy() = {};
  else if (w[1] == "track") s.track.clear();
  else ctx.Fail("expected poses, keys, springs, output, energy or track after 'clear', got '" + w[1] + "'");
}

void Schedule(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  RequireObject(s, ctx, "schedule");
  if (w[1] == "off") {
    s.scene.control().schedule.resize(0, 0);
    return;
  }
  try {
    s.scene.control().schedule =
        formats::ReadTargetSchedule(w[1], s.scene.object().mode_names(), s.scene.options().dt);
  } catch (const formats::ParseError& e) {
    ctx.Fail(std::string("schedule: ") + e.what());
  }
  s.out << "schedule: " << s.scene.control().schedule.cols() << " steps of targets from " << w[1] << "\n";
  if (s.scene.options().integrator != Integrator::kThesis)  // wobble fit spacetime's
    s.out << "schedule: note: the targets were fitted with the thesis integrator; this script steps with "
          << IntegratorName(s.scene.options().integrator) << " ('set integrator thesis' replays the fit)\n";
}

void Output(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 3);
  s.output_runs.clear();
  if (w[1] == "off") {
    s.output_path.clear();
    return;
  }
  int every = 1;
  if (w.size() == 3 && (!formats::detail::ParseInt(w[2], &every) || every < 1))
    ctx.Fail("expected EVERY as a whole number >= 1, got '" + w[2] + "'");
  try {
    formats::CheckWritable(w[1]);
  } catch (const std::runtime_error& e) {
    ctx.Fail(std::string("output: ") + e.what());
  }
  s.output_path = w[1];
  s.output_every = every;
}

void Print(State& s, const Words& w, const Context& ctx) {
  if (s.scene.has_bodies()) return ScenePrint(s, w, ctx);
  ctx.ExpectWords(w, 1, 1);
  RequireObject(s, ctx, "print");
  const Eigen::VectorXd &q = s.scene.object().q(), &qd = s.scene.object().qd();
  s.out << "t = " << Num(s.scene.time()) << "  q = [";
  for (int i = 0; i < q.size(); ++i) s.out << (i ? " " : "") << Num(q[i]);
  s.out << "]  dq = [";
  for (int i = 0; i < qd.size(); ++i) s.out << (i ? " " : "") << Num(qd[i]);
  s.out << "]  control energy " << Num(s.scene.control_energy().consumed) << "\n";
}

void Render(State& s, const Words& w, const Context& ctx) {
  if (s.scene.has_bodies()) return SceneRender(s, w, ctx);
  if (w.size() < 2) ctx.Fail("expected '" + ctx.usage + "'");
  RequireObject(s, ctx, "render");
  RenderRequest request;
  request.dir = w[1];
  for (size_t i = 2; i < w.size(); ++i) {
    const size_t eq = w[i].find('=');
    if (eq == std::string::npos) {
      if (i != 2) ctx.Fail("expected NAME=VALUE after the outputs, got '" + w[i] + "'");
      request.what = w[i];
      continue;
    }
    const std::string name = w[i].substr(0, eq);
    if (!scene::IsRenderOption(name))
      ctx.Fail("unknown render option '" + name + "' (" + scene::RenderOptionNames() + ")");
    request.options.emplace_back(name, w[i].substr(eq + 1));
  }
  if (s.track.empty()) ctx.Fail("render: nothing to draw yet (run 'simul' or 'keyframe' first)");
  if (!s.render_hook) ctx.Fail("render: this program has no renderer ('wobble run' and Python's Interpreter have one, built with VTK)");
  const auto merged = std::make_shared<const record::Trajectory>(scene::MergeRuns(s.track));
  const record::BodyInfo& body = merged->bodies()[0];
  request.world = body.ffd<2>() ? s.scene.ObjectWorldOptions(*body.ffd<2>()) : s.scene.ObjectWorldOptions(*body.ffd<3>());
  request.trajectory = merged;
  try {
    s.render_hook(request);
  } catch (const std::exception& e) {
    ctx.Fail(std::string("render: ") + e.what());
  }
}

void Echo(State& s, const Words& w, const Context&) {
  for (size_t i = 1; i < w.size(); ++i) s.out << (i > 1 ? " " : "") << w[i];
  s.out << "\n";
}

void Help(State& s, const Words&, const Context&) { s.out << Interpreter::Help(); }

void Quit(State& s, const Words&, const Context&) { s.quit = true; }

}  // namespace wobble::script
