#include "cli_common.h"
#include "wobble/formats/csv.h"

#include <filesystem>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <unistd.h>

#include <iostream>

#include "wobble/analysis/conditioning.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/heightfield_file.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/object_file.h"
#include "wobble/scene/ffd_object.h"
#ifdef WOBBLE_HAVE_PIPELINES
#include "pipelines/mesh_io.h"
#endif

namespace wobble::app {

void AddBodyFlags(CLI::App* cmd, BodyFiles* files) {
  cmd->add_option("--object", files->object, "Object file: lattice, mass points, drawing")
      ->required()
      ->type_name("FILE");
  cmd->add_option("--modes", files->modes, "Deformation files; the modes of all files, in order")
      ->required()
      ->delimiter(',')
      ->type_name("FILE[,FILE...]");
}

namespace {
// Refuses a mode set that cannot be simulated, and warns of a poor one.
template <class Body> void CheckLoadedModes(const Body& body, const std::string& object_file) {
  const analysis::ModeSetReport report = analysis::CheckModeSet(body);
  if (report.level == analysis::ModeSetReport::Level::kError) {
    std::string msg = "the modes of " + object_file + " cannot be simulated:";
    for (const std::string& m : report.messages) msg += "\n  " + m;
    throw std::invalid_argument(msg + "\n(wobble condition check explains the mode set)");
  }
  for (const std::string& m : report.messages) std::cerr << "wobble: warning: " << m << "\n";
}

// The object file: a 3D one's `mesh` line is read by VTK when the CLI has the pipelines.
template <int Dim> BodyDefN<Dim> ReadObject(const std::string& path) {
#ifdef WOBBLE_HAVE_PIPELINES
  return pipelines::ReadObject<Dim>(path);
#else
  return formats::ReadObjectFile<Dim>(path);
#endif
}
}  // namespace

template <int Dim> std::shared_ptr<const BodyModelN<Dim>> LoadBody(const BodyFiles& files, bool check_modes) {
  BodyDefN<Dim> def = ReadObject<Dim>(files.object);
  std::vector<DeformationModeN<Dim>> modes;
  for (const std::string& path : files.modes) {
    if (path.empty()) throw UsageError("--modes: empty file name in the list");
    const std::vector<DeformationModeN<Dim>> more = formats::ReadDeformationFile(path, def.lattice);
    modes.insert(modes.end(), more.begin(), more.end());
  }
  auto body = std::make_shared<const BodyModelN<Dim>>(std::move(def), std::move(modes));
  if (check_modes) CheckLoadedModes(*body, files.object);
  return body;
}
template std::shared_ptr<const BodyModel> LoadBody<2>(const BodyFiles&, bool);
template std::shared_ptr<const BodyModelN<3>> LoadBody<3>(const BodyFiles&, bool);

void CheckOutputFolder(const std::string& folder) {
  CheckOutputFile("--out", (std::filesystem::path(folder) / ".wobble-probe").string());  // leaves nothing behind
}

void CheckOutputFile(const std::string& flag, const std::string& path) {
  if (path.empty()) return;
  try {
    formats::CheckWritable(path);
  } catch (const std::runtime_error& e) {
    throw UsageError(flag + ": " + e.what());
  }
}

void AddLimitFlags(CLI::App* cmd, Limits* limits) {
  cmd->add_option("--max-steps", limits->max_steps, "Refuse runs of more steps than this")->capture_default_str();
  cmd->add_option("--max-record-mb", limits->max_record_mb, "Refuse runs whose record would take more MiB")
      ->capture_default_str();
}

void CheckLimitFlags(const Limits& limits) {
  if (limits.max_steps < 1 || limits.max_steps > kMaxStepsLimit)
    throw UsageError("--max-steps must be between 1 and " + std::to_string(kMaxStepsLimit));
  RequirePositive(limits.max_record_mb, "--max-record-mb");
}

long CheckRunLimits(double duration, double dt, long every, int columns, const Limits& limits) {
  CheckLimitFlags(limits);
  const long steps = RunSteps(duration, dt, limits, "raise it with --max-steps N");
  CheckRecordSize((double(steps) / double(std::max(1L, every)) + 2.0) * double(columns), limits,
                  "raise it with --max-record-mb N" + std::string(every > 0 ? ", or keep fewer rows (--every)" : ""));
  return steps;
}

// The words of a list separated by commas and/or white space.
std::vector<std::string> ListWords(const std::string& text) {
  std::string t = text;
  for (char& c : t)
    if (c == ',') c = ' ';
  std::istringstream in(t);
  std::vector<std::string> words;
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

std::vector<double> ParseNumbers(const std::string& text, const std::string& flag) {
  std::vector<double> out;
  for (const std::string& word : ListWords(text)) {
    double v = 0.0;
    if (!formats::detail::ParseNumber(word, &v)) throw UsageError(flag + ": '" + word + "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

void AddWorldFlags(CLI::App* cmd, WorldFlags* f) {
  cmd->add_flag("--no-gravity", f->no_gravity, "Switch gravity off (default: g = 9.81 along -y)");
  cmd->add_flag("--no-ground", f->no_ground, "No ground at all");
  cmd->add_option("--ground-height", f->ground_height, "Height of the ground line at x = 0")
      ->type_name("Y")
      ->capture_default_str();
  cmd->add_option("--ground-slope", f->ground_slope_deg, "Slope of the ground line, degrees counter-clockwise")
      ->type_name("DEG")
      ->capture_default_str();
  cmd->add_option("--ground-stiffness", f->ground_stiffness, "Penalty stiffness K_d (appendix C: grconst)")
      ->type_name("K")
      ->capture_default_str();
  cmd->add_option("--ground-damping", f->ground_damping, "Damping along the ground normal (grdam)")
      ->type_name("C")
      ->capture_default_str();
  cmd->add_option("--friction-damping", f->friction_damping, "Damping along the ground tangent (frconst)")
      ->type_name("F")
      ->capture_default_str();
  cmd->add_option("--friction-cap", f->friction_cap, "Largest |friction / normal force| (frsin)")
      ->type_name("TAN")
      ->capture_default_str();
  cmd->add_option("--terrain", f->terrain,
                  "A terrain in place of the ground line: its profile through these points, left to right, solid "
                  "below (two at the same x: a cliff); the ground flags above are its faces' parameters")
      ->type_name("\"X1 Y1 X2 Y2 ..\"");
  cmd->add_option("--terrain-face", f->terrain_faces,
                  "A terrain segment's own constants (1-based, left to right), as a script's terrain_face: e.g. an icy "
                  "slope \"3 frsin 0.05\"; NAME is grconst, grdam, frconst or frsin; repeat for more segments")
      ->type_name("\"SEGMENT NAME VALUE ..\"");
  cmd->add_option("--heightfield", f->heightfield,
                  "3D objects: the ground is this heightfield y = h(x, z) ('origin X0 Z0', 'spacing DX DZ', a row of "
                  "heights per z) in place of the plane; the ground flags above are its constants")
      ->type_name("FILE");
}

namespace {

// --terrain-face "SEGMENT NAME VALUE .." (each may repeat) as one override per segment.
std::vector<SurfaceOverrides> TerrainFaces(const std::vector<std::string>& specs, int segments) {
  std::vector<SurfaceOverrides> faces;
  if (specs.empty()) return faces;
  faces.resize(size_t(segments));
  for (const std::string& spec : specs) {
    std::istringstream in(spec);
    std::vector<std::string> w;
    for (std::string word; in >> word;) w.push_back(word);
    const std::string where = "--terrain-face \"" + spec + "\": ";
    if (w.size() < 3 || w.size() % 2 == 0) throw UsageError(where + "expected SEGMENT NAME VALUE [NAME VALUE ..]");
    int index = 0;
    if (!formats::detail::ParseInt(w[0], &index) || index < 1 || index > segments)
      throw UsageError(where + "expected a segment from 1 to " + std::to_string(segments) + ", got '" + w[0] + "'");
    for (size_t i = 1; i + 1 < w.size(); i += 2) {
      double value;
      if (!formats::detail::ParseNumber(w[i + 1], &value) || value < 0)
        throw UsageError(where + "expected a number >= 0 for " + w[i] + ", got '" + w[i + 1] + "'");
      if (!faces[size_t(index - 1)].Set(w[i], value))
        throw UsageError(where + "expected grconst, grdam, frconst or frsin, got '" + w[i] + "'");
    }
  }
  return faces;
}

}  // namespace

WorldParams MakeWorldParams(const WorldFlags& f) {
  RequireFinite(f.ground_height, "--ground-height");
  RequireFinite(f.ground_slope_deg, "--ground-slope");
  if (std::abs(f.ground_slope_deg) >= 90.0) throw UsageError("--ground-slope must be between -90 and 90 degrees");
  RequireNonNegative(f.ground_stiffness, "--ground-stiffness");
  RequireNonNegative(f.ground_damping, "--ground-damping");
  RequireNonNegative(f.friction_damping, "--friction-damping");
  RequireNonNegative(f.friction_cap, "--friction-cap");
  WorldParams p;
  p.gravity_on = !f.no_gravity;
  p.ground.enabled = !f.no_ground;
  p.ground.point = Eigen::Vector2d(0.0, f.ground_height);
  p.ground.slope = f.ground_slope_deg * M_PI / 180.0;
  p.ground.stiffness = f.ground_stiffness;
  p.ground.normal_damping = f.ground_damping;
  p.ground.friction_damping = f.friction_damping;
  p.ground.friction_cap = f.friction_cap;
  if (!f.terrain.empty()) {
    const std::vector<double> xy = ParseNumbers(f.terrain, "--terrain");
    if (xy.size() < 4 || xy.size() % 2) throw UsageError("--terrain: expected pairs X Y, at least two, got " +
                                                         std::to_string(xy.size()) + " numbers");
    std::vector<Eigen::Vector2d> vertices;
    for (size_t i = 0; i + 1 < xy.size(); i += 2) vertices.emplace_back(xy[i], xy[i + 1]);
    const std::vector<SurfaceOverrides> segments = TerrainFaces(f.terrain_faces, int(vertices.size()) - 1);
    try {
      p.ground.terrain = Terrain::Make(std::move(vertices), segments);
    } catch (const InputError& e) {
      throw UsageError(std::string("--terrain: ") + e.what());
    }
  } else if (!f.terrain_faces.empty()) {
    throw UsageError("--terrain-face needs a --terrain");
  }
  if (!f.heightfield.empty()) p.ground.heightfield = formats::ReadHeightfieldFile(f.heightfield);
  return p;
}

namespace {
template <int Dim> void LoadStartingBody(const BodyFiles& files, const std::string& q, const std::string& qdot, StartingWorld* s) {
  const std::shared_ptr<const BodyModelN<Dim>> body = LoadBody<Dim>(files);
  s->q0 = ParseCoordinates(q, "--q", *body);
  s->qd0 = ParseVelocities(qdot, "--qdot", *body);
  std::get<Dim - 2>(s->bodies) = body;
}
}  // namespace

StartingWorld LoadStartingWorld(const BodyFiles& files, const std::string& q, const std::string& qdot,
                                const WorldFlags& flags, Integrator integrator, double dt) {
  StartingWorld s;
  s.options.params = MakeWorldParams(flags);
  s.options.integrator = integrator;
  s.options.dt = dt;
  if (formats::ObjectFileDimension(files.object) == 3) {
    // the 3D ground: the plane through y = height, tilted by the slope about z as the 2D line
    s.options.params.ground_plane = GroundPlaneOf(s.options.params.ground);
    LoadStartingBody<3>(files, q, qdot, &s);
  } else {
    LoadStartingBody<2>(files, q, qdot, &s);
  }
  return s;
}

World StartingWorld::MakeWorld() const {
  World world(options);
  if (dim() == 3) world.AddBody(body<3>());
  else world.AddBody(body<2>());
  // 3D: q = (t, rotation vector r, γ), R = exp([r]×) the turn by |r| radians about r; 2D: the state
  world.SetCoordinates(0, q0, qd0);
  return world;
}

template <int Dim> std::string CoordinateNames(const BodyModelN<Dim>& body) {
  std::string names = Dim == 3 ? "tx ty tz rx ry rz" : "tx ty theta";
  for (int d = 1; d <= body.num_modes(); ++d) names += " g" + std::to_string(d);
  return names;
}

template <int Dim> std::string VelocityNames(const BodyModelN<Dim>& body) {
  if constexpr (Dim == 2) return CoordinateNames(body);  // q̇ = dq/dt
  std::string names = "vx vy vz wx wy wz";
  for (int d = 1; d <= body.num_modes(); ++d) names += " dg" + std::to_string(d);
  return names;
}

template <int Dim>
Eigen::VectorXd ParseCoordinates(const std::string& text, const std::string& what, const BodyModelN<Dim>& body) {
  return ParseNumbers(text, what, body.num_q(), CoordinateNames(body), body.name());
}

template <int Dim>
Eigen::VectorXd ParseVelocities(const std::string& text, const std::string& what, const BodyModelN<Dim>& body) {
  return ParseNumbers(text, what, body.num_q(), VelocityNames(body), body.name());
}

template std::string CoordinateNames(const BodyModel&);
template std::string CoordinateNames(const BodyModelN<3>&);
template std::string VelocityNames(const BodyModel&);
template std::string VelocityNames(const BodyModelN<3>&);
template Eigen::VectorXd ParseCoordinates(const std::string&, const std::string&, const BodyModel&);
template Eigen::VectorXd ParseCoordinates(const std::string&, const std::string&, const BodyModelN<3>&);
template Eigen::VectorXd ParseVelocities(const std::string&, const std::string&, const BodyModel&);
template Eigen::VectorXd ParseVelocities(const std::string&, const std::string&, const BodyModelN<3>&);

Eigen::VectorXd ParseNumbers(const std::string& text, const std::string& what, int expected_size,
                             const std::string& names, const std::string& body_name) {
  std::vector<double> values;
  std::string token;
  auto flush = [&]() {
    if (token.empty()) return;
    // the one number grammar of wobble's files (subnormals are finite numbers: accepted)
    double v = 0.0;
    if (!formats::detail::ParseNumber(token, &v)) {
      char* end = nullptr;
      std::strtod(token.c_str(), &end);  // only to tell "inf", "nan" and 1e999 from words
      if (end != token.c_str() + token.size())
        throw UsageError(what + ": '" + token + "' is not a number (expected " + std::to_string(expected_size) +
                         " numbers: " + names + ")");
      throw UsageError(what + ": '" + token + "' is not a finite number");
    }
    values.push_back(v);
    token.clear();
  };
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == ',' || c == '\n') {
      flush();
    } else {
      token += c;
    }
  }
  flush();
  if (values.empty() && text.find_first_not_of(" \t,\n") == std::string::npos)
    return Eigen::VectorXd::Zero(expected_size);
  if (int(values.size()) != expected_size) {
    std::ostringstream msg;
    msg << what << ": got " << values.size() << " number" << (values.size() == 1 ? "" : "s") << " but body '"
        << body_name << "' has " << expected_size << " generalized coordinates (" << names << ")";
    throw UsageError(msg.str());
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), Eigen::Index(values.size()));
}

void RequireFinite(double value, const std::string& what) {
  if (!std::isfinite(value)) throw UsageError(what + " must be a finite number");
}
void RequirePositive(double value, const std::string& what) {
  if (!std::isfinite(value) || !(value > 0.0)) throw UsageError(what + " must be a positive number");
}
void RequireNonNegative(double value, const std::string& what) {
  if (!std::isfinite(value) || value < 0.0) throw UsageError(what + " must be a non-negative number");
}

Integrator ParseIntegratorFlag(const std::string& name) {
  Integrator integrator;
  if (ParseIntegrator(name, &integrator)) return integrator;
  throw UsageError("--integrator: '" + name + "' is not one of " + IntegratorNames());
}

std::string StateFlagHelp(const std::string& default_text) {
  return "Initial q: 2D \"tx ty theta g1 .. gD\"; 3D (a 'dimension 3' object) \"tx ty tz rx ry rz g1 .. gD\", "
         "r a rotation vector: the turn by |r| radians about r (" +
         default_text + ")";
}

std::string VelocityFlagHelp(const std::string& default_text) {
  return "Initial q-dot: 2D the layout of --q; 3D \"vx vy vz wx wy wz dg1 .. dgD\", v the velocity of the body "
         "origin, w the angular velocity in the body frame (" +
         default_text + ")";
}

std::string IntegratorFlagHelp() { return "One of " + IntegratorNames(); }

// A one-line "iteration N, cost C" on stderr when it is a terminal (quiet otherwise).
std::function<void(int, double)> IterationLine() {
  if (isatty(STDERR_FILENO) != 1) return {};
  return [](int iteration, double cost) {
    std::fprintf(stderr, "\r  iteration %4d  cost %-14.6g", iteration, cost);
    std::fflush(stderr);
  };
}
void EndIterationLine() {
  if (isatty(STDERR_FILENO) == 1) std::fprintf(stderr, "\n");
}

}  // namespace wobble::app
