// The interpreter's Witkin & Welch commands (README "Scripts": bodies, constraints, motion
// control and goal behaviours): linear bodies in a World, named points, nails and
// attachments made at once, and behaviours (trajectory, chase, connect, grab, release, on/off,
// impulse, wait, wait_for) queued in a Sequencer that runs them between steps of `simul`.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "wobble/script/interpreter.h"
#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

using namespace script_detail;

namespace {

// "2d"/"3d" (or 2/3).
template <class C> int Dimension(const std::string& word, const C& ctx) {
  if (word == "2d" || word == "2D" || word == "2") return 2;
  if (word == "3d" || word == "3D" || word == "3") return 3;
  ctx.Fail("expected 2d or 3d, got '" + word + "'");
}

template <class C> double NonNegative(const std::string& word, const std::string& what, const C& ctx) {
  const double v = Number(word, what, ctx);
  if (v < 0) ctx.Fail("expected a non-negative " + what + ", got " + word);
  return v;
}

template <class C> double Positive(const std::string& word, const std::string& what, const C& ctx) {
  const double v = Number(word, what, ctx);
  if (!(v > 0)) ctx.Fail("expected a positive " + what + ", got " + word);
  return v;
}

// `count` numbers from w[first] on, as a vector.
template <class C>
Eigen::VectorXd Vector(const std::vector<std::string>& w, size_t first, int count, const std::string& what, const C& ctx) {
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

const std::vector<std::string> kSceneCommands = {"linear", "ffd", "point", "place", "nail", "attach", "path", "trajectory",
                                                 "impulse", "chase", "connect", "grab", "release", "on", "off",
                                                 "wait", "wait_for", "record"};

}  // namespace

Interpreter::Scene& Interpreter::EnsureScene() {
  if (!scene_) {
    WorldOptions o;
    o.params = world_.params;
    o.dt = world_.dt;
    scene_ = std::make_unique<Scene>(o);
  }
  return *scene_;
}

const World* Interpreter::scene() const { return scene_ ? &scene_->world : nullptr; }

Eigen::VectorXd Interpreter::ScenePoint(const std::string& name) const {
  if (!scene_ || !scene_->anchors.count(name)) throw std::out_of_range("no scene point '" + name + "'");
  return scene_->anchors.at(name).Position(scene_->world);
}

int Interpreter::SceneConstraint(const std::string& name) const {
  if (!scene_) return -1;
  const auto it = scene_->constraints.find(name);
  return it == scene_->constraints.end() || !scene_->world.exists(it->second) ? -1 : it->second;
}

World* Interpreter::mutable_scene() { return scene_ ? &scene_->world : nullptr; }

SceneRenderRequest Interpreter::SceneDrawing() {
  if (!scene_) throw std::logic_error("SceneDrawing: the script made no scene");
  SceneRenderRequest req;
  req.azimuth = scene_->azimuth;
  req.elevation = scene_->elevation;
  req.world = &scene_->world;
  req.drawings = &scene_->drawings;
  for (const auto& [name, a] : scene_->anchors) req.anchors.push_back(a);
  return req;
}

void Interpreter::SyncSceneOptions() {
  // the interpreter's parameters apply to the scene's world
  WorldOptions& o = scene_->world.mutable_options();
  o.dt = world_.dt;
  o.params.gravity_on = world_.params.gravity_on;
  o.params.ground = world_.params.ground;
}

bool Interpreter::SceneStep(const std::function<void(const std::string&)>& log) {
  Scene& s = *scene_;
  control::BehaviourContext bctx{&s.world, &s.constraints};
  s.sequencer.BeforeStep(bctx, log);
  // names made by behaviours are no longer promised
  for (const auto& kv : s.constraints) s.promised.erase(kv.first);
  return s.world.Step();
}

void Interpreter::StepScene() {
  if (!scene_ || scene_->world.num_bodies() == 0) throw std::logic_error("StepScene: the script made no scene");
  SyncSceneOptions();
  if (!SceneStep([&](const std::string& line) { out_ << "  " << line << "\n"; }))
    throw SimulationStopped("simulation stopped: " + scene_->world.status().message);
  time_ = scene_->world.time();
}

const std::vector<record::SceneFrame>& Interpreter::recorded_frames() const {
  static const std::vector<record::SceneFrame> none;
  return scene_ ? scene_->frames : none;
}

bool Interpreter::SetSceneParameter(const std::string& name, const std::string& value, const Context& ctx) {
  if (name == "feedback_rate") {
    EnsureScene().world.mutable_options().feedback_rate = Positive(value, name, ctx);
  } else if (name == "view_azimuth") {
    EnsureScene().azimuth = Number(value, name, ctx);
  } else if (name == "view_elevation") {
    const double e = Number(value, name, ctx);
    if (std::abs(e) >= 90) ctx.Fail("expected an elevation between -90 and 90 degrees, got " + value);
    EnsureScene().elevation = e;
  } else {
    return false;
  }
  return true;
}

bool Interpreter::ExecuteScene(const std::vector<std::string>& w, const Context& ctx) {
  const std::string& cmd = w[0];
  const bool has_scene = scene_ && scene_->world.num_bodies() > 0;
  if (std::find(kSceneCommands.begin(), kSceneCommands.end(), cmd) == kSceneCommands.end() &&
      !(has_scene && (cmd == "simul" || cmd == "print" || cmd == "render")))
    return false;
  auto usage = [&]() -> std::string {
    for (const CommandInfo& c : Commands())
      if (c.name == cmd) return c.usage;
    return cmd;
  };
  Scene& s = EnsureScene();
  World& world = s.world;

  // a named point or place
  auto anchor = [&](const std::string& name) -> const control::Anchor& {
    const auto it = s.anchors.find(name);
    if (it == s.anchors.end()) {
      const std::string near = Nearest(name, Keys(s.anchors));
      ctx.Fail("no point or place named '" + name + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") +
               " (define it with 'point' or 'place'; known: " + Join(Keys(s.anchors)) + ")");
    }
    return it->second;
  };
  auto body_point = [&](const std::string& name, const std::string& role) -> const control::Anchor& {
    const control::Anchor& a = anchor(name);
    if (a.fixed()) ctx.Fail(role + " '" + name + "' is a fixed place; expected a point of a body ('point')");
    return a;
  };
  auto dim_of = [&](const control::Anchor& a) { return a.fixed() ? int(a.place.size()) : world.dim(a.point->body); };
  auto new_constraint_name = [&](const std::string& name) {
    if (s.constraints.count(name) && world.exists(s.constraints.at(name)))
      ctx.Fail("a constraint named '" + name + "' exists already");
    if (s.promised.count(name)) ctx.Fail("a queued behaviour will make a constraint named '" + name + "' already");
  };
  auto known_constraint = [&](const std::string& name) {
    const bool now = s.constraints.count(name) && world.exists(s.constraints.at(name));
    if (!now && !s.promised.count(name)) {
      std::vector<std::string> names = Keys(s.constraints);
      names.insert(names.end(), s.promised.begin(), s.promised.end());
      const std::string near = Nearest(name, names);
      ctx.Fail("no constraint named '" + name + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") +
               " (known: " + Join(names) + ")");
    }
  };
  // optional velocity words from w[first]: none or exactly `dim` numbers
  auto optional_velocity = [&](size_t first, int dim) -> std::optional<Eigen::VectorXd> {
    if (w.size() == first) return std::nullopt;
    if (w.size() != first + dim)
      ctx.Fail("expected '" + usage() + "' with " + std::to_string(dim) + " velocity components or none");
    return Vector(w, first, dim, "a velocity component", ctx);
  };

  if (cmd == "linear") {
    // linear NAME 2d|3d affine|quadratic box HX HY [HZ] | pyramid W H   [options]
    if (w.size() < 6) ctx.Fail("expected '" + usage() + "'");
    const std::string& name = w[1];
    if (s.bodies.count(name)) ctx.Fail("a body named '" + name + "' exists already");
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
      else if (key == "at") {
        at = Vector(w, i + 1, dim, "the position after 'at'", ctx);
        i += dim;
      } else {
        const std::string near = Nearest(key, {"grid", "levels", "mass", "at", "ke", "kc", "kd", "kq"});
        ctx.Fail("unknown option '" + key + "' of linear" + (near.empty() ? "" : "; did you mean '" + near + "'?"));
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
    const int b = world.AddLinearBody(model, material);
    world.SetLinearState(b, model->PlacedState(Eigen::MatrixXd::Identity(dim, dim), at),
                         Eigen::MatrixXd::Zero(dim, model->basis_size()));
    s.bodies[name] = b;
    s.drawings.resize(world.num_bodies());
    s.drawings[b] = shape == "box" ? MakeBoxDrawing(sizes, 8) : MakePyramidDrawing(dim, sizes[0], sizes[1], 8);
  } else if (cmd == "ffd") {
    // ffd NAME: the loaded FFD object (load_obj, load_def, assign, set_vec q/dq) joins the scene
    ExpectWords(w, 2, 2, usage(), ctx);
    const std::string& name = w[1];
    if (s.bodies.count(name)) ctx.Fail("a body named '" + name + "' exists already");
    RequireBody(ctx, "ffd");
    const std::shared_ptr<const BodyModel> body = BuildBody();
    const int b = world.AddBody(body);
    world.SetState(b, q_, qd_);
    s.bodies[name] = b;
    s.drawings.resize(world.num_bodies());  // FFD bodies draw their own shape
  } else if (cmd == "point") {
    // point NAME BODY U1 U2 [U3]
    if (w.size() < 4) ctx.Fail("expected '" + usage() + "'");
    if (s.anchors.count(w[1])) ctx.Fail("a point or place named '" + w[1] + "' exists already");
    const auto it = s.bodies.find(w[2]);
    if (it == s.bodies.end()) {
      const std::string near = Nearest(w[2], Keys(s.bodies));
      ctx.Fail("no body named '" + w[2] + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") +
               " (known: " + Join(Keys(s.bodies)) + ")");
    }
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
    s.anchors[w[1]] = control::PointAnchor(w[1], point);
  } else if (cmd == "place") {
    ExpectWords(w, 4, 5, usage(), ctx);
    if (s.anchors.count(w[1])) ctx.Fail("a point or place named '" + w[1] + "' exists already");
    s.anchors[w[1]] = control::PlaceAnchor(w[1], Vector(w, 2, int(w.size()) - 2, "a coordinate", ctx));
  } else if (cmd == "nail") {
    // nail NAME POINT [X Y [Z]]: at once
    if (w.size() < 3) ctx.Fail("expected '" + usage() + "'");
    new_constraint_name(w[1]);
    const control::Anchor& a = body_point(w[2], "nail");
    const int dim = dim_of(a);
    Eigen::VectorXd where;
    if (w.size() > 3) {
      if (int(w.size()) != 3 + dim) ctx.Fail("expected " + std::to_string(dim) + " coordinates for where to nail, or none");
      where = Vector(w, 3, dim, "a coordinate", ctx);
    }
    s.constraints[w[1]] = world.AddNail(*a.point, where);
  } else if (cmd == "attach") {
    ExpectWords(w, 4, 4, usage(), ctx);
    new_constraint_name(w[1]);
    const control::Anchor& a = body_point(w[2], "attach");
    const control::Anchor& b = body_point(w[3], "attach");
    if (dim_of(a) != dim_of(b)) ctx.Fail("cannot attach a 2D point to a 3D one");
    s.constraints[w[1]] = world.AddAttachment(*a.point, *b.point);
  } else if (cmd == "path") {
    // path NAME 2d|3d T X Y [Z] T X Y [Z] ...
    if (w.size() < 3) ctx.Fail("expected '" + usage() + "'");
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
    s.paths[w[1]] = std::make_shared<const control::KeyframeSpline>(times, keys);
  } else if (cmd == "trajectory") {
    // trajectory NAME POINT PATH [preroll DT]: queued
    if (w.size() != 4 && w.size() != 6) ctx.Fail("expected '" + usage() + "'");
    new_constraint_name(w[1]);
    const control::Anchor& a = body_point(w[2], "trajectory");
    const auto it = s.paths.find(w[3]);
    if (it == s.paths.end()) {
      const std::string near = Nearest(w[3], Keys(s.paths));
      ctx.Fail("no path named '" + w[3] + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") +
               " (define it with 'path')");
    }
    if (it->second->dim() != dim_of(a)) ctx.Fail("path '" + w[3] + "' and point '" + w[2] + "' differ in dimension");
    double preroll = 0.0;
    if (w.size() == 6) {
      if (w[4] != "preroll") ctx.Fail("expected 'preroll DT' after the path, got '" + w[4] + "'");
      preroll = NonNegative(w[5], "preroll time", ctx);
    }
    s.promised.insert(w[1]);
    s.sequencer.Add(std::make_unique<control::Follow>(a, it->second, it->second->start_time(), preroll, w[1]));
  } else if (cmd == "impulse") {
    if (w.size() < 2) ctx.Fail("expected '" + usage() + "'");
    const control::Anchor& a = body_point(w[1], "impulse");
    const int dim = dim_of(a);
    if (int(w.size()) != 2 + dim) ctx.Fail("expected " + std::to_string(dim) + " velocity components after 'impulse " + w[1] + "'");
    s.sequencer.Add(std::make_unique<control::Impulse>(a, Vector(w, 2, dim, "a velocity component", ctx)));
  } else if (cmd == "chase" || cmd == "grab") {
    // chase|grab POINT TARGET DURATION [VX VY [VZ]]
    if (w.size() < 4) ctx.Fail("expected '" + usage() + "'");
    const control::Anchor& a = body_point(w[1], cmd);
    const control::Anchor& target = anchor(w[2]);
    if (dim_of(a) != dim_of(target)) ctx.Fail("'" + w[1] + "' and '" + w[2] + "' differ in dimension");
    const double duration = Positive(w[3], "DURATION", ctx);
    std::optional<Eigen::VectorXd> v = optional_velocity(4, dim_of(a));
    if (cmd == "chase") {
      s.sequencer.Add(std::make_unique<control::Chase>(a, target, duration, v));
    } else {
      const std::string name = "connect:" + w[1];
      new_constraint_name(name);
      s.promised.insert(name);
      s.sequencer.AddGrab(a, target, duration, v, name);
    }
  } else if (cmd == "connect") {
    ExpectWords(w, 3, 4, usage(), ctx);
    const control::Anchor& a = body_point(w[1], "connect");
    const control::Anchor& target = anchor(w[2]);
    if (dim_of(a) != dim_of(target)) ctx.Fail("'" + w[1] + "' and '" + w[2] + "' differ in dimension");
    const std::string name = w.size() == 4 ? w[3] : "connect:" + w[1];
    new_constraint_name(name);
    s.promised.insert(name);
    s.sequencer.Add(std::make_unique<control::Connect>(a, target, name));
  } else if (cmd == "release") {
    ExpectWords(w, 2, 2, usage(), ctx);
    known_constraint(w[1]);
    s.promised.erase(w[1]);
    s.sequencer.Add(std::make_unique<control::Release>(w[1]));
  } else if (cmd == "on" || cmd == "off") {
    ExpectWords(w, 2, 2, usage(), ctx);
    known_constraint(w[1]);
    s.sequencer.Add(std::make_unique<control::Switch>(w[1], cmd == "on"));
  } else if (cmd == "wait") {
    ExpectWords(w, 2, 2, usage(), ctx);
    s.sequencer.Add(std::make_unique<control::Wait>(NonNegative(w[1], "DURATION", ctx)));
  } else if (cmd == "wait_for") {
    // wait_for time T | near A B R | below A Y | above A Y
    if (w.size() < 3) ctx.Fail("expected '" + usage() + "'");
    const std::string& kind = w[1];
    std::string text;
    for (size_t i = 1; i < w.size(); ++i) text += (i > 1 ? " " : "") + w[i];
    std::function<bool(const World&)> pred;
    if (kind == "time") {
      ExpectWords(w, 3, 3, "wait_for time T", ctx);
      const double t = Number(w[2], "T", ctx);
      pred = [t](const World& cw) { return cw.time() + 0.5 * cw.options().dt >= t; };
    } else if (kind == "near") {
      ExpectWords(w, 5, 5, "wait_for near A B R", ctx);
      const control::Anchor a = anchor(w[2]), b = anchor(w[3]);
      if (dim_of(a) != dim_of(b)) ctx.Fail("'" + w[2] + "' and '" + w[3] + "' differ in dimension");
      const double r = Positive(w[4], "distance R", ctx);
      pred = [a, b, r](const World& cw) { return (a.Position(cw) - b.Position(cw)).norm() <= r; };
    } else if (kind == "below" || kind == "above") {
      ExpectWords(w, 4, 4, "wait_for " + kind + " A Y", ctx);
      const control::Anchor a = anchor(w[2]);
      const double y = Number(w[3], "Y", ctx);
      const bool below = kind == "below";
      pred = [a, y, below](const World& cw) {
        const double h = a.Position(cw)[1];
        return below ? h <= y : h >= y;
      };
    } else {
      ctx.Fail("expected 'time', 'near', 'below' or 'above' after wait_for, got '" + kind + "'");
    }
    s.sequencer.Add(std::make_unique<control::WaitFor>(text, pred));
  } else if (cmd == "record") {
    ExpectWords(w, 2, 2, usage(), ctx);
    if (w[1] == "off") {
      s.record_fps = 0.0;
    } else {
      s.record_fps = Positive(w[1], "FPS", ctx);
      s.next_frame = world.time();
    }
  } else if (cmd == "render") {
    // render DIR [WHAT], WHAT a comma list of frames, filmstrip, vtp (the FFD form is in script.cc)
    ExpectWords(w, 2, 3, usage(), ctx);
    SceneRenderRequest req;
    req.folder = w[1];
    req.name = std::filesystem::path(ctx.file).stem().string();
    if (req.name.empty() || req.name == "<stdin>" || req.name == "<prompt>") req.name = "scene";
    if (w.size() > 2) {
      req.frames = req.filmstrip = req.vtp = false;
      std::stringstream list(w[2]);
      for (std::string item; std::getline(list, item, ',');) {
        if (item == "frames") req.frames = true;
        else if (item == "filmstrip") req.filmstrip = true;
        else if (item == "vtp") req.vtp = true;
        else ctx.Fail("expected a comma list of frames, filmstrip, vtp after 'render DIR' for a scene, got '" + item + "'");
      }
    }
    if (s.frames.empty()) ctx.Fail("nothing was recorded: 'record FPS' before 'simul'");
    if (!scene_render_hook_) ctx.Fail("render: this program cannot draw (wobble run draws through pipelines/, built with VTK)");
    const SceneRenderRequest drawing = SceneDrawing();
    req.azimuth = drawing.azimuth;
    req.elevation = drawing.elevation;
    req.world = drawing.world;
    req.drawings = drawing.drawings;
    req.anchors = drawing.anchors;
    req.recorded = &s.frames;
    const record::SceneFrame now = record::CaptureFrame(world);
    std::vector<std::string> files;
    try {
      files = scene_render_hook_(req);
    } catch (const std::exception& e) {
      record::RestoreFrame(world, now);
      ctx.Fail(std::string("render: ") + e.what());
    }
    record::RestoreFrame(world, now);
    out_ << "render: " << s.frames.size() << " recorded frames\n";
    for (const std::string& f : files) out_ << "  " << f << "\n";
  } else if (cmd == "simul") {
    ExpectWords(w, 1, 2, usage(), ctx);
    double duration = end_ - world.time();
    if (w.size() == 2) duration = NonNegative(w[1], "DURATION", ctx);
    else if (duration < 0) ctx.Fail("end (" + Num(end_) + ") is before the scene's time (" + Num(world.time()) + ")");
    SyncSceneOptions();
    const double dt = world_.dt;
    const long steps = std::lround(duration / dt);
    // explicit stepping of stiff energies on a thin body blows up: say so before it does
    for (const auto& [name, b] : s.bodies) {
      if (world.kind(b) != BodyKind::kLinear) continue;
      const double stable = StableTimeStep(world.linear_model(b), world.material(b));
      if (dt > stable)
        out_ << "warning: dt " << Num(dt) << " is above the stable step " << Num(stable) << " of body '" << name
             << "' (its energies k_e, k_c, k_q on its thinnest axis); the run may stop with a non-finite state: "
                "set dt below that, or soften or thicken the body\n";
    }
    control::BehaviourContext bctx{&world, &s.constraints};
    auto log = [&](const std::string& line) { out_ << "  " << line << "\n"; };
    auto record = [&]() {
      if (s.record_fps <= 0 || world.time() + 0.5 * dt < s.next_frame) return;
      if (s.frames.empty() || s.frames.back().time < world.time() - 0.5 * dt) s.frames.push_back(record::CaptureFrame(world));
      s.next_frame += 1.0 / s.record_fps;
      while (s.next_frame <= world.time() + 0.5 * dt) s.next_frame += 1.0 / s.record_fps;
    };
    record();
    for (long n = 0; n < steps; ++n) {
      bool stepped = false;
      try {
        stepped = SceneStep(log);
      } catch (const control::BehaviourError& e) {
        ctx.Fail(std::string("at t = ") + Num(world.time()) + ": " + e.what());
      }
      if (!stepped)
        throw SimulationStopped(ctx.file + ":" + std::to_string(ctx.line) + ": simulation stopped: " + world.status().message);
      record();
      if (progress_ && (n % 64 == 0 || n + 1 == steps)) progress_(double(n + 1) / double(steps), world.time());
    }
    // behaviours due at the end time act now (a Connect at a chase's contact time at the end)
    if (steps > 0) {
      try {
        s.sequencer.BeforeStep(bctx, log);
      } catch (const control::BehaviourError& e) {
        ctx.Fail(std::string("at t = ") + Num(world.time()) + ": " + e.what());
      }
      for (const auto& kv : s.constraints) s.promised.erase(kv.first);
    }
    time_ = world.time();
    out_ << "simul: t = " << Num(world.time()) << ", " << steps << " steps; energy " << Num(world.TotalEnergy())
         << ", largest constraint violation " << Num(world.MaxViolation())
         << (s.sequencer.idle() ? "" : ", behaviours pending: " + std::to_string(s.sequencer.pending())) << "\n";
  } else if (cmd == "print") {
    ExpectWords(w, 1, 1, usage(), ctx);
    out_ << "t = " << Num(world.time()) << "  energy " << Num(world.TotalEnergy()) << "  largest constraint violation "
         << Num(world.MaxViolation()) << "\n";
    for (const auto& [name, a] : s.anchors) {
      out_ << "  " << name;
      const Eigen::VectorXd x = a.Position(world);
      for (int i = 0; i < x.size(); ++i) out_ << " " << Num(x[i]);
      out_ << "\n";
    }
  }
  return true;
}

}  // namespace wobble::script
