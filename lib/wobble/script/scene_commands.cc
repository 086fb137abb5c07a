// The interpreter's Witkin & Welch commands (README "Scripts": bodies, constraints, motion
// control and goal behaviours): linear bodies in the scene's World, named points, nails and
// attachments made at once, and behaviours (trajectory, chase, connect, grab, release, on/off,
// impulse, wait, wait_for) queued in the scene's Sequencer, which acts between the steps of
// `simul` (scene::Scene runs it as a World controller).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

using namespace script_detail;

namespace {

// "2d"/"3d" (or 2/3).
int Dimension(const std::string& word, const Context& ctx) {
  if (word == "2d" || word == "2D" || word == "2") return 2;
  if (word == "3d" || word == "3D" || word == "3") return 3;
  ctx.Fail("expected 2d or 3d, got '" + word + "'");
}

// `count` numbers from w[first] on, as a vector.
Eigen::VectorXd Vector(const Words& w, size_t first, int count, const std::string& what, const Context& ctx) {
  if (first + count > w.size()) ctx.Fail("expected " + std::to_string(count) + " numbers for " + what);
  Eigen::VectorXd v(count);
  for (int i = 0; i < count; ++i) v[i] = Number(w[first + i], what, ctx);
  return v;
}

std::string Join(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

template <class M> std::vector<std::string> Keys(const M& map) {
  std::vector<std::string> k;
  for (const auto& kv : map) k.push_back(kv.first);
  return k;
}

// A named point or place.
const control::Anchor& AnchorNamed(scene::Scene& sc, const std::string& name, const Context& ctx) {
  const auto it = sc.anchors().find(name);
  if (it == sc.anchors().end())
    ctx.Fail("no point or place named '" + name + "'" + DidYouMean(name, Keys(sc.anchors())) +
             " (define it with 'point' or 'place'; known: " + Join(Keys(sc.anchors())) + ")");
  return it->second;
}

// A named point of a body (not a fixed place), for `role`.
const control::Anchor& BodyPoint(scene::Scene& sc, const std::string& name, const std::string& role, const Context& ctx) {
  const control::Anchor& a = AnchorNamed(sc, name, ctx);
  if (a.fixed()) ctx.Fail(role + " '" + name + "' is a fixed place; expected a point of a body ('point')");
  return a;
}

int DimOf(scene::Scene& sc, const control::Anchor& a) { return a.fixed() ? int(a.place.size()) : sc.world().dim(a.point->body); }

void RequireSameDim(scene::Scene& sc, const control::Anchor& a, const control::Anchor& b, const Context& ctx) {
  if (DimOf(sc, a) != DimOf(sc, b)) ctx.Fail("'" + a.name + "' and '" + b.name + "' differ in dimension");
}

// A name no constraint has or will have.
void RequireNewConstraintName(scene::Scene& sc, const std::string& name, const Context& ctx) {
  if (sc.Constraint(name) >= 0) ctx.Fail("a constraint named '" + name + "' exists already");
  if (sc.promised().count(name)) ctx.Fail("a queued behaviour will make a constraint named '" + name + "' already");
}

// A name a constraint has, or a queued behaviour will give one.
void RequireKnownConstraint(scene::Scene& sc, const std::string& name, const Context& ctx) {
  if (sc.Constraint(name) >= 0 || sc.promised().count(name)) return;
  std::vector<std::string> names = Keys(sc.constraints());
  names.insert(names.end(), sc.promised().begin(), sc.promised().end());
  ctx.Fail("no constraint named '" + name + "'" + DidYouMean(name, names) + " (known: " + Join(names) + ")");
}

// Optional velocity words from w[first]: none or exactly `dim` numbers.
std::optional<Eigen::VectorXd> OptionalVelocity(const Words& w, size_t first, int dim, const Context& ctx) {
  if (w.size() == first) return std::nullopt;
  if (w.size() != first + dim)
    ctx.Fail("expected '" + ctx.usage + "' with " + std::to_string(dim) + " velocity components or none");
  return Vector(w, first, dim, "a velocity component", ctx);
}

void RequireNewBodyName(const scene::Scene& sc, const std::string& name, const Context& ctx) {
  if (sc.bodies().count(name)) ctx.Fail("a body named '" + name + "' exists already");
}

void RequireNewAnchorName(const scene::Scene& sc, const std::string& name, const Context& ctx) {
  if (sc.anchors().count(name)) ctx.Fail("a point or place named '" + name + "' exists already");
}

}  // namespace

void Linear(State& s, const Words& w, const Context& ctx) {
  // linear NAME 2d|3d affine|quadratic box HX HY [HZ] | pyramid W H   [options]
  if (w.size() < 6) ctx.Fail("expected '" + ctx.usage + "'");
  const std::string& name = w[1];
  RequireNewBodyName(s.scene, name, ctx);
  const int dim = Dimension(w[2], ctx);
  LinearOrder order;
  if (w[3] == "affine") order = LinearOrder::kAffine;
  else if (w[3] == "quadratic") order = LinearOrder::kQuadratic;
  else ctx.Fail("expected affine or quadratic, got '" + w[3] + "'");
  const std::string& shape = w[4];
  size_t i = 5;
  Eigen::VectorXd sizes;
  if (shape == "box") {
    sizes = Vector(w, i, dim, "a half extent", ctx);
    i += dim;
  } else if (shape == "pyramid") {
    sizes = Vector(w, i, 2, "the pyramid's half width and height", ctx);
    i += 2;
  } else {
    ctx.Fail("expected box or pyramid, got '" + shape + "'");
  }
  if (!(sizes.minCoeff() > 0)) ctx.Fail("expected positive sizes");
  int grid = 3, levels = 3;
  double mass = 1.0;
  Eigen::VectorXd at = Eigen::VectorXd::Zero(dim);
  AffineMaterial material;
  bool ground = false;
  auto whole = [&](const std::string& word, const std::string& what, int min) {
    int v;
    if (!formats::detail::ParseInt(word, &v) || v < min)
      ctx.Fail("expected " + what + " as a whole number >= " + std::to_string(min) + ", got '" + word + "'");
    return v;
  };
  while (i < w.size()) {
    const std::string& key = w[i];
    auto next = [&]() -> const std::string& {
      if (i + 1 >= w.size()) ctx.Fail("expected a value after '" + key + "'");
      return w[++i];
    };
    if (key == "grid") grid = whole(next(), "grid", 2);
    else if (key == "levels") levels = whole(next(), "levels", 2);
    else if (key == "mass") mass = Positive(next(), "mass", ctx);
    else if (key == "ke") material.rigidity = NonNegative(next(), "ke", ctx);
    else if (key == "kc") material.volume = NonNegative(next(), "kc", ctx);
    else if (key == "kd") material.damping = NonNegative(next(), "kd", ctx);
    else if (key == "kq") material.bending = NonNegative(next(), "kq", ctx);
    else if (key == "ground") ground = true;
    else if (key == "at") {
      at = Vector(w, i + 1, dim, "the position after 'at'", ctx);
      i += dim;
    } else {
      ctx.Fail("unknown option '" + key + "' of linear" +
               DidYouMean(key, {"grid", "levels", "mass", "at", "ke", "kc", "kd", "kq", "ground"}));
    }
    ++i;
  }
  LinearBodyDef def = shape == "box" ? MakeBoxBody(name, dim, order, sizes, grid, mass)
                                     : MakePyramidBody(name, dim, order, sizes[0], sizes[1], levels, grid, mass);
  std::shared_ptr<const LinearBodyModel> model;
  try {
    model = std::make_shared<const LinearBodyModel>(std::move(def));
  } catch (const std::invalid_argument& e) {
    ctx.Fail(e.what());
  }
  const int body = s.scene.AddLinearBody(
      name, model, material, at, shape == "box" ? MakeBoxDrawing(sizes, 8) : MakePyramidDrawing(dim, sizes[0], sizes[1], 8));
  if (ground) s.scene.world().SetGroundContact(body, true);
}

void Ffd(State& s, const Words& w, const Context& ctx) {
  // ffd NAME: the loaded FFD object (load_obj, load_def, assign, set_vec q/dq) joins the scene
  ctx.ExpectWords(w, 2, 2);
  RequireNewBodyName(s.scene, w[1], ctx);
  RequireObject(s, ctx, "ffd");
  s.scene.AddObjectBody(w[1]);
}

void PointCommand(State& s, const Words& w, const Context& ctx) {
  // point NAME BODY U1 U2 [U3]
  if (w.size() < 4) ctx.Fail("expected '" + ctx.usage + "'");
  RequireNewAnchorName(s.scene, w[1], ctx);
  const auto it = s.scene.bodies().find(w[2]);
  if (it == s.scene.bodies().end())
    ctx.Fail("no body named '" + w[2] + "'" + DidYouMean(w[2], Keys(s.scene.bodies())) +
             " (known: " + Join(Keys(s.scene.bodies())) + ")");
  const World& world = s.scene.world();
  const int dim = world.dim(it->second);
  if (int(w.size()) != 3 + dim)
    ctx.Fail("expected " + std::to_string(dim) + " undeformed coordinates for a point of the " + std::to_string(dim) +
             "D body '" + w[2] + "'");
  const MaterialPoint point = At(it->second, Vector(w, 3, dim, "a coordinate", ctx));
  try {
    world.PointPosition(point);  // lattice coordinates of an FFD body must lie in [0, 1]²
  } catch (const std::invalid_argument& e) {
    ctx.Fail(std::string("point ") + w[1] + ": " + e.what());
  }
  s.scene.AddAnchor(control::PointAnchor(w[1], point));
}

void Place(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 4, 5);
  RequireNewAnchorName(s.scene, w[1], ctx);
  s.scene.AddAnchor(control::PlaceAnchor(w[1], Vector(w, 2, int(w.size()) - 2, "a coordinate", ctx)));
}

void Nail(State& s, const Words& w, const Context& ctx) {
  // nail NAME POINT [X Y [Z]]: at once
  if (w.size() < 3) ctx.Fail("expected '" + ctx.usage + "'");
  scene::Scene& sc = s.scene;
  RequireNewConstraintName(sc, w[1], ctx);
  const control::Anchor& a = BodyPoint(sc, w[2], "nail", ctx);
  const int dim = DimOf(sc, a);
  Eigen::VectorXd where;
  if (w.size() > 3) {
    if (int(w.size()) != 3 + dim) ctx.Fail("expected " + std::to_string(dim) + " coordinates for where to nail, or none");
    where = Vector(w, 3, dim, "a coordinate", ctx);
  }
  sc.constraints()[w[1]] = sc.world().AddNail(*a.point, where);
}

void Attach(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 4, 4);
  scene::Scene& sc = s.scene;
  RequireNewConstraintName(sc, w[1], ctx);
  const control::Anchor& a = BodyPoint(sc, w[2], "attach", ctx);
  const control::Anchor& b = BodyPoint(sc, w[3], "attach", ctx);
  if (DimOf(sc, a) != DimOf(sc, b)) ctx.Fail("cannot attach a 2D point to a 3D one");
  sc.constraints()[w[1]] = sc.world().AddAttachment(*a.point, *b.point);
}

void PathCommand(State& s, const Words& w, const Context& ctx) {
  // path NAME 2d|3d T X Y [Z] T X Y [Z] ...
  if (w.size() < 3) ctx.Fail("expected '" + ctx.usage + "'");
  const int dim = Dimension(w[2], ctx);
  const size_t per_key = size_t(dim) + 1;
  if ((w.size() - 3) % per_key != 0 || w.size() - 3 < 2 * per_key)
    ctx.Fail("expected at least two keys of " + std::to_string(per_key) + " numbers (T and " + std::to_string(dim) +
             " coordinates) after 'path " + w[1] + " " + w[2] + "'");
  std::vector<double> times;
  std::vector<Eigen::VectorXd> keys;
  for (size_t i = 3; i < w.size(); i += per_key) {
    times.push_back(Number(w[i], "a key time", ctx));
    keys.push_back(Vector(w, i + 1, dim, "a key coordinate", ctx));
  }
  const std::string invalid = control::KeyframeSpline::Validate(times, keys, {});
  if (!invalid.empty()) ctx.Fail("path " + w[1] + ": " + invalid);
  s.scene.paths()[w[1]] = std::make_shared<const control::KeyframeSpline>(times, keys);
}

void TrajectoryCommand(State& s, const Words& w, const Context& ctx) {
  // trajectory NAME POINT PATH [preroll DT]: queued
  if (w.size() != 4 && w.size() != 6) ctx.Fail("expected '" + ctx.usage + "'");
  scene::Scene& sc = s.scene;
  RequireNewConstraintName(sc, w[1], ctx);
  const control::Anchor& a = BodyPoint(sc, w[2], "trajectory", ctx);
  const auto it = sc.paths().find(w[3]);
  if (it == sc.paths().end())
    ctx.Fail("no path named '" + w[3] + "'" + DidYouMean(w[3], Keys(sc.paths())) + " (define it with 'path')");
  if (it->second->dim() != DimOf(sc, a)) ctx.Fail("path '" + w[3] + "' and point '" + w[2] + "' differ in dimension");
  double preroll = 0.0;
  if (w.size() == 6) {
    if (w[4] != "preroll") ctx.Fail("expected 'preroll DT' after the path, got '" + w[4] + "'");
    preroll = NonNegative(w[5], "preroll time", ctx);
  }
  sc.promised().insert(w[1]);
  sc.sequencer().Add(std::make_unique<control::Follow>(a, it->second, it->second->start_time(), preroll, w[1]));
}

void ImpulseCommand(State& s, const Words& w, const Context& ctx) {
  if (w.size() < 2) ctx.Fail("expected '" + ctx.usage + "'");
  scene::Scene& sc = s.scene;
  const control::Anchor& a = BodyPoint(sc, w[1], "impulse", ctx);
  const int dim = DimOf(sc, a);
  if (int(w.size()) != 2 + dim) ctx.Fail("expected " + std::to_string(dim) + " velocity components after 'impulse " + w[1] + "'");
  sc.sequencer().Add(std::make_unique<control::Impulse>(a, Vector(w, 2, dim, "a velocity component", ctx)));
}

void ChaseOrGrab(State& s, const Words& w, const Context& ctx) {
  // chase|grab POINT TARGET DURATION [VX VY [VZ]]
  if (w.size() < 4) ctx.Fail("expected '" + ctx.usage + "'");
  scene::Scene& sc = s.scene;
  const control::Anchor& a = BodyPoint(sc, w[1], w[0], ctx);
  const control::Anchor& target = AnchorNamed(sc, w[2], ctx);
  RequireSameDim(sc, a, target, ctx);
  const double duration = Positive(w[3], "DURATION", ctx);
  std::optional<Eigen::VectorXd> v = OptionalVelocity(w, 4, DimOf(sc, a), ctx);
  if (w[0] == "chase") {
    sc.sequencer().Add(std::make_unique<control::Chase>(a, target, duration, v));
    return;
  }
  const std::string name = "connect:" + w[1];
  RequireNewConstraintName(sc, name, ctx);
  sc.promised().insert(name);
  sc.sequencer().AddGrab(a, target, duration, v, name);
}

void ConnectCommand(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 3, 4);
  scene::Scene& sc = s.scene;
  const control::Anchor& a = BodyPoint(sc, w[1], "connect", ctx);
  const control::Anchor& target = AnchorNamed(sc, w[2], ctx);
  RequireSameDim(sc, a, target, ctx);
  const std::string name = w.size() == 4 ? w[3] : "connect:" + w[1];
  RequireNewConstraintName(sc, name, ctx);
  sc.promised().insert(name);
  sc.sequencer().Add(std::make_unique<control::Connect>(a, target, name));
}

void ReleaseCommand(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  RequireKnownConstraint(s.scene, w[1], ctx);
  s.scene.promised().erase(w[1]);
  s.scene.sequencer().Add(std::make_unique<control::Release>(w[1]));
}

void OnOff(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  RequireKnownConstraint(s.scene, w[1], ctx);
  s.scene.sequencer().Add(std::make_unique<control::Switch>(w[1], w[0] == "on"));
}

void WaitCommand(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  s.scene.sequencer().Add(std::make_unique<control::Wait>(NonNegative(w[1], "DURATION", ctx)));
}

void WaitForCommand(State& s, const Words& w, const Context& ctx) {
  // wait_for time T | near A B R | below A Y | above A Y
  if (w.size() < 3) ctx.Fail("expected '" + ctx.usage + "'");
  scene::Scene& sc = s.scene;
  const std::string& kind = w[1];
  std::string text;
  for (size_t i = 1; i < w.size(); ++i) text += (i > 1 ? " " : "") + w[i];
  auto expect = [&](size_t n, const std::string& usage) {
    if (w.size() != n) ctx.Fail("expected '" + usage + "'");
  };
  std::function<bool(const World&)> pred;
  if (kind == "time") {
    expect(3, "wait_for time T");
    const double t = Number(w[2], "T", ctx);
    pred = [t](const World& cw) { return cw.time() + 0.5 * cw.options().dt >= t; };
  } else if (kind == "near") {
    expect(5, "wait_for near A B R");
    const control::Anchor a = AnchorNamed(sc, w[2], ctx), b = AnchorNamed(sc, w[3], ctx);
    RequireSameDim(sc, a, b, ctx);
    const double r = Positive(w[4], "distance R", ctx);
    pred = [a, b, r](const World& cw) { return (a.Position(cw) - b.Position(cw)).norm() <= r; };
  } else if (kind == "below" || kind == "above") {
    expect(4, "wait_for " + kind + " A Y");
    const control::Anchor a = AnchorNamed(sc, w[2], ctx);
    const double y = Number(w[3], "Y", ctx);
    const bool below = kind == "below";
    pred = [a, y, below](const World& cw) {
      const double h = a.Position(cw)[1];
      return below ? h <= y : h >= y;
    };
  } else {
    ctx.Fail("expected 'time', 'near', 'below' or 'above' after wait_for, got '" + kind + "'");
  }
  sc.sequencer().Add(std::make_unique<control::WaitFor>(text, pred));
}

void RecordCommand(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  s.scene.Record(w[1] == "off" ? 0.0 : Positive(w[1], "FPS", ctx));
}

void SceneSimul(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 1, 2);
  scene::Scene& sc = s.scene;
  World& world = sc.world();
  double duration = sc.end() - world.time();
  if (w.size() == 2) duration = NonNegative(w[1], "DURATION", ctx);
  else if (duration < 0) ctx.Fail("end (" + Num(sc.end()) + ") is before the scene's time (" + Num(world.time()) + ")");
  // explicit stepping of stiff energies on a thin body blows up: say so before it does
  const double dt = sc.options().dt;
  for (const auto& [name, b] : sc.bodies()) {
    if (world.kind(b) != BodyKind::kLinear) continue;
    const double stable = StableTimeStep(world.linear_model(b), world.material(b));
    if (dt > stable)
      s.out << "warning: dt " << Num(dt) << " is above the stable step " << Num(stable) << " of body '" << name
            << "' (its energies k_e, k_c, k_q on its thinnest axis); the run may stop with a non-finite state: "
               "set dt below that, or soften or thicken the body\n";
  }
  scene::RunReport r;
  try {
    r = sc.Simulate(duration, StepObserver(s, false));
  } catch (const control::BehaviourError& e) {
    ctx.Fail(std::string("at t = ") + Num(world.time()) + ": " + e.what());
  }
  if (!r.ok()) throw SimulationStopped(ctx.file + ":" + std::to_string(ctx.line) + ": simulation stopped: " + r.status.message);
  s.out << "simul: t = " << Num(world.time()) << ", " << r.steps << " steps; energy " << Num(world.TotalEnergy())
        << ", largest constraint violation " << Num(world.MaxViolation())
        << (sc.sequencer().idle() ? "" : ", behaviours pending: " + std::to_string(sc.sequencer().pending())) << "\n";
}

void ScenePrint(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 1, 1);
  const World& world = s.scene.world();
  s.out << "t = " << Num(world.time()) << "  energy " << Num(world.TotalEnergy()) << "  largest constraint violation "
        << Num(world.MaxViolation()) << "\n";
  for (const auto& [name, a] : s.scene.anchors()) {
    s.out << "  " << name;
    const Eigen::VectorXd x = a.Position(world);
    for (int i = 0; i < x.size(); ++i) s.out << " " << Num(x[i]);
    s.out << "\n";
  }
}

void SceneRender(State& s, const Words& w, const Context& ctx) {
  // render DIR [WHAT], WHAT a comma list of kSceneRenderWords (the FFD form: object_commands.cc)
  ctx.ExpectWords(w, 2, 3);
  SceneRenderRequest req;
  req.folder = w[1];
  req.name = std::filesystem::path(ctx.file).stem().string();
  if (req.name.empty() || req.name == "<stdin>" || req.name == "<prompt>") req.name = "scene";
  if (w.size() > 2) {
    req.what.clear();
    std::stringstream list(w[2]);
    for (std::string item; std::getline(list, item, ',');) {
      if (std::find(kSceneRenderWords.begin(), kSceneRenderWords.end(), item) == kSceneRenderWords.end()) {
        std::string words;
        for (const std::string& word : kSceneRenderWords) words += (words.empty() ? "" : ", ") + word;
        ctx.Fail("expected a comma list of " + words + " after 'render DIR' for a scene, got '" + item + "'");
      }
      req.what.push_back(item);
    }
  }
  req.fps = s.scene.record_fps();
  req.recorded = s.scene.recorded();
  if (!req.recorded || req.recorded->empty()) ctx.Fail("nothing was recorded: 'record FPS' before 'simul'");
  if (!s.scene_render_hook) ctx.Fail("render: this program cannot draw (wobble run draws through pipelines/, built with VTK)");
  req.drawing = s.scene.Drawing();
  req.world = s.scene.world().options();
  std::vector<std::string> files;
  try {
    files = s.scene_render_hook(req);
  } catch (const std::exception& e) {
    ctx.Fail(std::string("render: ") + e.what());
  }
  s.out << "render: " << req.recorded->size() << " recorded frames\n";
  for (const std::string& f : files) s.out << "  " << f << "\n";
}

}  // namespace wobble::script
