#include "condition.h"

#include "wobble/core/distribute.h"
#include "wobble/core/interrupt.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "wobble/formats/atomic_file.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/object_file.h"
#include "wobble/analysis/conditioning.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/formats/object_file.h"

#ifdef WOBBLE_HAVE_PIPELINES
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>

#include "pipelines/charts.h"
#include "pipelines/condition_charts.h"
#include "pipelines/energy_charts.h"
#include "pipelines/exports.h"
#include "pipelines/exr_io.h"
#include "pipelines/scene_view.h"
#endif

namespace wobble::app {
namespace {

constexpr double kPi = 3.14159265358979323846;

double Deg(double rad) { return rad * 180.0 / kPi; }
double Rad(double deg) { return deg * kPi / 180.0; }

// The sweep's φ samples: from, from + step, ..., and `to` itself (so that π/2 is always there).
std::vector<double> Angles(const ConditionSweepArgs& a) {
  RequireFinite(a.from_deg, "--from");
  RequireFinite(a.to_deg, "--to");
  RequirePositive(a.step_deg, "--step");
  if (!(a.to_deg > a.from_deg)) throw UsageError("--to must be larger than --from");
  std::vector<double> phis;
  // counted as a double first: a tiny --step would overflow an int and skip the check
  const long n = CheckedCount(std::floor((a.to_deg - a.from_deg) / a.step_deg + 1e-9), 0, 100000,
                              "the sweep's samples ((--to - --from) / --step)", "use a larger --step");
  for (long i = 0; i <= n; ++i) phis.push_back(Rad(a.from_deg + double(i) * a.step_deg));
  if (Deg(phis.back()) < a.to_deg - 1e-9) phis.push_back(Rad(a.to_deg));
  if (std::abs(a.to_deg - 90.0) < 1e-12) phis.back() = kPi / 2;  // exactly the singular case
  return phis;
}

#ifdef WOBBLE_HAVE_PIPELINES
using pipelines::ConditionGrid;

// .vti for ParaView: point arrays cond and log10cond (NaN where singular) and singular (0/1).
void WriteGridVti(const std::string& path, const ConditionGrid& g) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(g.nx, g.ny, 1);
  image->SetOrigin(g.x0, g.y0, 0.0);
  image->SetSpacing(g.dx, g.ny > 1 ? g.dy : 1.0, 1.0);
  auto add = [&](const char* name, auto value) {
    auto a = vtkSmartPointer<vtkDoubleArray>::New();
    a->SetName(name);
    a->SetNumberOfTuples(vtkIdType(g.cond.size()));
    for (size_t i = 0; i < g.cond.size(); ++i) a->SetValue(vtkIdType(i), value(g.cond[i]));
    image->GetPointData()->AddArray(a);
  };
  add("cond", [](double c) { return std::isfinite(c) ? c : std::nan(""); });
  add("log10cond", [](double c) { return std::isfinite(c) ? std::log10(c) : std::nan(""); });
  add("singular", [](double c) { return std::isfinite(c) ? 0.0 : 1.0; });
  pipelines::WriteVti(path, image);
}

// The map as EXR (float channels cond and log10cond, +inf where singular; rows from the top as
// EXR has them), .vti, and a colour-mapped PNG when there is a display.
void WriteMapFiles(const std::filesystem::path& out, const ConditionGrid& g) {
  std::vector<float> cond, log_cond;
  for (int j = g.ny - 1; j >= 0; --j)
    for (int i = 0; i < g.nx; ++i) {
      const double c = g.cond[size_t(j) * g.nx + i];
      cond.push_back(float(c));
      log_cond.push_back(std::isfinite(c) ? float(std::log10(c)) : INFINITY);
    }
  pipelines::WriteExrChannels((out / "map.exr").string(), g.nx, g.ny, {{"cond", cond}, {"log10cond", log_cond}});
  WriteGridVti((out / "map.vti").string(), g);
  if (pipelines::HasDisplay())
    pipelines::WriteScalarFieldPng(pipelines::ConditionMapField(g, "phi (degrees)", "gamma1 (vertical squash)"),
                                   (out / "map.png").string());
}
#endif

std::string CondText(const analysis::ConditionNumber& c) {
  if (c.singular) return "singular";
  std::ostringstream o;
  o << std::setprecision(6) << c.cond;
  return o.str();
}

}  // namespace

ConditionCommands AddConditionCommand(CLI::App* app, ConditionSweepArgs* s, ConditionCheckArgs* c,
                                      ConditionTimeArgs* t) {
  CLI::App* cond = app->add_subcommand("condition", "Conditioning of the mass matrix (thesis §4.10.3)");
  cond->require_subcommand(1);

  CLI::App* sweep = cond->add_subcommand(
      "sweep", "cond(M) against the angle between a vertical squash and a squash rotated by phi (Fig. 4.7, 4.8)");
  sweep->add_option("--object", s->object, "Object file (its lattice and mass points)")->capture_default_str();
  sweep->add_option("--from", s->from_deg, "First angle, degrees")->capture_default_str();
  sweep->add_option("--to", s->to_deg, "Last angle, degrees (90: both modes are the vertical squash)")
      ->capture_default_str();
  sweep->add_option("--step", s->step_deg, "Angle step, degrees")->capture_default_str();
  sweep->add_option("--compress", s->compress, "Squash: squeeze along its axis (displacement per unit length)")
      ->capture_default_str();
  sweep->add_option("--expand", s->expand, "Squash: bulge across its axis")->capture_default_str();
  sweep->add_option("--q", s->q, "State \"tx ty theta g1 g2\" (default: rest)");
  sweep->add_option("--drop-last", s->drop_last, "Samples left out of the small-angle chart (Fig. 4.8)")
      ->capture_default_str();
  sweep->add_option("--map", s->map_size, "Also map cond over phi and the squash amplitude g1, N x N samples")
      ->capture_default_str();
  sweep->add_option("--map-gamma", s->map_gamma, "The map's g1 range is [-G, G]")->capture_default_str();
  sweep->add_option("--out", s->out, "Output folder")->capture_default_str();

  CLI::App* check = cond->add_subcommand(
      "check", "How close the modes are to each other and to the rigid motions; which modes the mass cannot see");
  AddBodyFlags(check, &c->files);
  check->add_option("--q", c->q, "State \"tx ty theta g1 ..\" (default: rest)");
  check->add_option("--warn-angle", c->warn_angle_deg, "Warn below this angle, degrees")->capture_default_str();
  check->add_option("--warn-visibility", c->warn_visibility, "Warn below this visibility (0..1)")
      ->capture_default_str();
  check->add_option("--json", c->json, "Also write the report as JSON")->type_name("FILE");

  CLI::App* time = cond->add_subcommand(
      "time", "cond(M) against time as a body falls onto the ground, contacts marked (Fig. 4.9)");
  time->add_option("--object", t->files.object, "Object file")->capture_default_str();
  time->add_option("--modes", t->files.modes, "Deformation files")->delimiter(',')->capture_default_str();
  AddWorldFlags(time, &t->world);
  time->add_option("--q", t->q, "Initial state \"tx ty theta g1 ..\" (3D: \"tx ty tz rx ry rz g1 ..\")")->capture_default_str();
  time->add_option("--dt", t->dt, "Time step (thesis integrator)")->capture_default_str();
  time->add_option("--duration", t->duration, "Simulated time")->capture_default_str();
  time->add_option("--out", t->out, "Output folder")->capture_default_str();
  return {sweep, check, time};
}

int RunConditionSweep(const ConditionSweepArgs& a) {
  const bool three_d = formats::ObjectFileDimension(a.object) == 3;
  const std::vector<double> phis = Angles(a);
  RequirePositive(a.compress, "--compress");
  RequireFinite(a.expand, "--expand");
  if (a.drop_last < 0) throw UsageError("--drop-last must be >= 0");
  if (three_d && !a.q.empty()) throw UsageError("--q: a 3D body is swept at rest (its orientation is no coordinate)");
  if (three_d && a.map_size > 0) throw UsageError("--map: the condition map is 2D only so far");
  CheckOutputFolder(a.out);
  analysis::Squash squash;
  squash.compress = a.compress;
  squash.expand = a.expand;
  BodyDef def;
  Eigen::VectorXd q;
  std::vector<analysis::SweepSample> samples;
  if (three_d) {
    samples = analysis::AngleSweep(formats::ReadObjectFile<3>(a.object), phis, squash);
  } else {
    def = formats::ReadObjectFile(a.object);
    // a two-mode body only to parse --q against
    const BodyModel probe(def, {analysis::SquashMode(def.lattice, 0.0, squash, "v"),
                                analysis::SquashMode(def.lattice, 0.0, squash, "h")});
    q = ParseCoordinates(a.q, "--q", probe);
    samples = analysis::AngleSweep(def, phis, squash, q);
  }

  const std::filesystem::path out(a.out);
  std::vector<std::vector<double>> rows;
  for (const analysis::SweepSample& s : samples) {
    const Eigen::VectorXd& sv = s.cond.singular_values;
    rows.push_back({Deg(s.phi), s.phi, s.cond.cond, s.cond.cond_scaled, double(s.cond.singular), sv.maxCoeff(),
                    sv.minCoeff()});
  }
  const std::string csv = (out / "sweep.csv").string();
  formats::WriteCsvAtomically(csv, {"phi_deg", "phi_rad", "cond", "cond_scaled", "singular", "sigma_max", "sigma_min"}, rows);

  std::cout << "phi (deg)   cond(M)        cond(scaled)\n";
  for (const analysis::SweepSample& s : samples)
    std::cout << std::setw(9) << std::setprecision(5) << Deg(s.phi) << "   " << std::setw(12) << CondText(s.cond)
              << "   " << std::setw(12) << (s.cond.singular ? "singular" : std::to_string(s.cond.cond_scaled)) << "\n";
  for (const analysis::SweepSample& s : samples)
    if (s.cond.singular)
      std::cout << "at phi = " << Deg(s.phi)
                << " deg both modes are the vertical squash: M is singular (no finite condition number)\n";

#ifdef WOBBLE_HAVE_PIPELINES
  {
    ConditionGrid line;
    line.nx = int(samples.size());
    line.ny = 1;
    line.x0 = Deg(samples.front().phi);
    line.dx = samples.size() > 1 ? Deg(samples[1].phi - samples[0].phi) : 1.0;
    for (const analysis::SweepSample& s : samples) line.cond.push_back(s.cond.cond);
    WriteGridVti((out / "sweep.vti").string(), line);
  }
  if (pipelines::HasDisplay()) {
    pipelines::WriteChart(pipelines::SweepChart(samples), (out / "sweep.png").string(), "");
    pipelines::WriteChart(pipelines::SmallAngleChart(samples, a.drop_last), (out / "sweep_small_angle.png").string(), "");
  } else {
    std::cout << "no X display: charts skipped (run under xvfb-run -a)\n";
  }
#endif
  if (a.map_size > 0) {
    if (a.map_size < 2 || a.map_size > 2000) throw UsageError("--map must be between 2 and 2000");
    RequirePositive(a.map_gamma, "--map-gamma");
    // the rows on every thread and, under mpirun, on every rank (core/distribute.h): the same
    // numbers either way; a row Ctrl-C kept from starting comes back empty
    const std::vector<Bytes> rows = DistributedMap(size_t(a.map_size), MapOptions(), [&](size_t j) -> Bytes {
      if (InterruptRequested()) return Bytes();
      Eigen::VectorXd qj = q;
      qj[3] = -a.map_gamma + 2.0 * a.map_gamma * double(j) / (a.map_size - 1);
      std::vector<double> map_phis;
      for (int i = 0; i < a.map_size; ++i)
        map_phis.push_back(Rad(a.from_deg + (a.to_deg - a.from_deg) * i / (a.map_size - 1)));
      std::vector<double> row;
      for (const analysis::SweepSample& s : analysis::AngleSweep(def, map_phis, squash, qj))
        row.insert(row.end(), {Deg(s.phi), qj[3], s.cond.cond, s.cond.singular ? INFINITY : std::log10(s.cond.cond)});
      return ByteWriter().PutDoubles(row).Take();
    });
    std::vector<std::vector<double>> map_rows;
    for (size_t j = 0; j < rows.size(); ++j) {
      if (rows[j].empty())
        throw Interrupted("the map stopped by Ctrl-C before row " + std::to_string(j) + " of " +
                          std::to_string(a.map_size) + "; " + (out / "sweep.csv").string() + " is written, the map is not");
      const std::vector<double> row = ByteReader(rows[j]).GetDoubles();
      for (size_t k = 0; k + 4 <= row.size(); k += 4) map_rows.push_back({row[k], row[k + 1], row[k + 2], row[k + 3]});
    }
#ifdef WOBBLE_HAVE_PIPELINES
    ConditionGrid grid;  // the same numbers as the CSV, on their regular grid
    grid.nx = grid.ny = a.map_size;
    grid.x0 = a.from_deg;
    grid.dx = (a.to_deg - a.from_deg) / (a.map_size - 1);
    grid.y0 = -a.map_gamma;
    grid.dy = 2.0 * a.map_gamma / (a.map_size - 1);
    for (const std::vector<double>& r : map_rows) grid.cond.push_back(r[2]);
    WriteMapFiles(out, grid);
#endif
    formats::WriteCsvAtomically((out / "map.csv").string(), {"phi_deg", "gamma1", "cond", "log10cond"}, map_rows);
    std::cout << "map: " << (out / "map.csv").string() << "\n";
  }
  std::cout << "wrote " << out.string() << "/: sweep.csv";
#ifdef WOBBLE_HAVE_PIPELINES
  std::cout << ", sweep.vti" << (pipelines::HasDisplay() ? ", sweep.png, sweep_small_angle.png" : "");
  if (a.map_size > 0) std::cout << ", map.csv, map.exr, map.vti" << (pipelines::HasDisplay() ? ", map.png" : "");
#endif
  std::cout << "\n";
  return kExitOk;
}

int RunConditionTime(const ConditionTimeArgs& a) {
#ifndef WOBBLE_HAVE_PIPELINES
  (void)a;
  throw UsageError("condition time needs the pipelines (VTK), which this build does not have");
#else
  RequirePositive(a.dt, "--dt");
  RequirePositive(a.duration, "--duration");
  if (!(a.duration / a.dt <= 1e7)) throw UsageError("--duration / --dt asks for more than 10^7 steps");
  CheckOutputFolder(a.out);
  const StartingWorld setup = LoadStartingWorld(a.files, a.q, "", a.world, Integrator::kThesis, a.dt);
  const std::string name = setup.OnBody([](const auto& body) { return body.name(); });
  World world = setup.MakeWorld();

  // the run's trajectory: cond₂(M) and the contact events come from it, as for wobble render
  auto run = std::make_shared<record::Trajectory>(world);
  auto recorder = std::make_shared<record::Recorder>(run);
  world.SetRecorder(recorder);
  recorder->Start(world);
  const bool ok = world.RunUntil(a.duration);
  const std::filesystem::path out(a.out);
  const pipelines::ChartSpec spec =
      pipelines::ConditionChart(*run, 0, "cond(M) vs time: " + name + " falling onto the ground (Fig. 4.9)");
  const std::string png = pipelines::HasDisplay() ? (out / "cond_time.png").string() : "";
  pipelines::WriteChart(spec, png, (out / "cond_time.csv").string());
  std::cout << "wrote " << (out / "cond_time.csv").string() << " (" << run->size() << " samples, "
            << spec.markers.size() << " contact events, in cond_time_markers.csv)\n";
  if (png.empty())
    std::cout << "no X display: chart skipped (run under xvfb-run -a)\n";
  else
    std::cout << "wrote " << png << "\n";
  if (!ok) {
    std::cerr << "wobble: " << world.status().message << "\n";
    return kExitSimStopped;
  }
  return kExitOk;
#endif
}

namespace {
int PrintModeSetReport(const analysis::ModeSetReport& r, const std::string& body_name, const ConditionCheckArgs& a);
}  // namespace

int RunConditionCheck(const ConditionCheckArgs& a) {
  RequirePositive(a.warn_angle_deg, "--warn-angle");
  RequireNonNegative(a.warn_visibility, "--warn-visibility");
  CheckOutputFile("--json", a.json);
  analysis::ModeCheckOptions options;
  options.warn_angle_deg = a.warn_angle_deg;
  options.warn_visibility = a.warn_visibility;
  if (formats::ObjectFileDimension(a.files.object) == 3) {
    if (!a.q.empty()) throw UsageError("--q: a 3D body is checked at rest (its orientation is no coordinate)");
    const std::shared_ptr<const BodyModelN<3>> body = LoadBody<3>(a.files, /*check_modes=*/false);
    return PrintModeSetReport(analysis::CheckModeSet(*body, options), body->name(), a);
  }
  const std::shared_ptr<const BodyModel> body = LoadBody<2>(a.files, /*check_modes=*/false);
  return PrintModeSetReport(analysis::CheckModeSet(*body, ParseCoordinates(a.q, "--q", *body), options), body->name(), a);
}

namespace {
int PrintModeSetReport(const analysis::ModeSetReport& r, const std::string& body_name, const ConditionCheckArgs& a) {
  std::cout << "mode set of '" << body_name << "': " << analysis::LevelName(r.level) << "\n";
  for (const std::string& m : r.messages) std::cout << "  " << m << "\n";
  std::cout << "cond(M) = " << CondText(r.condition) << ", scaled " << r.condition.cond_scaled << "\n";
  std::cout << "mode          visibility  angle to the rest (deg)  closest combination\n";
  for (const analysis::ModeFinding& f : r.modes) {
    std::cout << "  " << std::left << std::setw(12) << f.mode << std::right << std::setw(10) << std::setprecision(3)
              << f.visibility << std::setw(18) << f.angle_to_others_deg << "       ";
    for (const analysis::Participant& p : f.closest_combination) std::cout << p.weight << " '" << p.dof << "' ";
    std::cout << "\n";
  }
  if (!a.json.empty()) {
    nlohmann::json j;
    j["level"] = analysis::LevelName(r.level);
    j["messages"] = r.messages;
    j["dofs"] = r.dofs;
    j["cond"] = r.condition.singular ? nlohmann::json(nullptr) : nlohmann::json(r.condition.cond);
    j["singular"] = r.condition.singular;
    j["cond_scaled"] = r.condition.cond_scaled;
    j["singular_values"] = std::vector<double>(r.condition.singular_values.data(),
                                               r.condition.singular_values.data() + r.condition.singular_values.size());
    j["smallest_angle_deg"] = r.smallest_angle_deg;
    j["smallest_mode"] = r.smallest_mode;
    nlohmann::json pairs = nlohmann::json::array();
    for (int i = 0; i < r.pair_angle_deg.rows(); ++i) {
      std::vector<double> row(r.pair_angle_deg.cols());
      for (int k = 0; k < r.pair_angle_deg.cols(); ++k) row[k] = r.pair_angle_deg(i, k);
      pairs.push_back(row);
    }
    j["pair_angle_deg"] = pairs;
    for (const analysis::ModeFinding& f : r.modes) {
      nlohmann::json combo = nlohmann::json::array();
      for (const analysis::Participant& p : f.closest_combination) combo.push_back({{"dof", p.dof}, {"weight", p.weight}});
      j["modes"].push_back({{"mode", f.mode}, {"visibility", f.visibility},
                            {"angle_to_others_deg", f.angle_to_others_deg}, {"closest_combination", combo}});
    }
    formats::WriteTextAtomically(a.json, j.dump(2) + "\n");
  }
  return r.level == analysis::ModeSetReport::Level::kError ? kExitBadInput : kExitOk;
}

}  // namespace

}  // namespace wobble::app
