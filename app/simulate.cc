#include "simulate.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "wobble/formats/atomic_file.h"
#include "wobble/formats/csv.h"
#include "wobble/record/trajectory_csv.h"
#include "progress.h"

namespace wobble::app {
namespace {

// Refuse runs whose CSV would not fit in memory comfortably.

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string VectorText(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (int i = 0; i < v.size(); ++i) s += (i ? " " : "") + Num(v[i]);
  return s + "]";
}

}  // namespace

CLI::App* AddSimulateCommand(CLI::App* app, SimulateArgs* a) {
  CLI::App* cmd = app->add_subcommand("simulate", "Simulate one body over the ground and write its trajectory as CSV");
  AddBodyFlags(cmd, &a->files);
  cmd->add_option("--q", a->q, StateFlagHelp("default: at rest at the origin"))->type_name("\"NUMS\"");
  cmd->add_option("--qdot", a->qdot, VelocityFlagHelp("default: zeros"))->type_name("\"NUMS\"");
  cmd->add_option("--integrator", a->integrator, IntegratorFlagHelp())
      ->capture_default_str()
      ->type_name("NAME");
  cmd->add_option("--dt", a->dt, "Time step")->capture_default_str();
  cmd->add_option("--duration", a->duration, "Simulated time")->capture_default_str();
  cmd->add_option("--every", a->every, "Write every Nth step (the first and last states always)")
      ->capture_default_str()
      ->type_name("N");
  AddWorldFlags(cmd, &a->world);
  cmd->add_option("--out", a->out, "CSV file to write (atomically: FILE.tmp, then renamed)")->type_name("FILE.csv");
  AddLimitFlags(cmd, &a->limits);
  cmd->footer(
      "Example:\n"
      "  wobble simulate --object data/table.obj --modes data/table_modes.def \\\n"
      "      --q \"0 50 0 0 0 0 0\" --duration 10 --out out/table_drop.csv\n"
      "  wobble simulate --object data/pot3.obj --modes data/pot3_modes.def3 \\\n"
      "      --q \"0 40 0 0.3 0 0.2 0 0 0\" --duration 2 --out out/pot3.csv");
  return cmd;
}

int RunSimulate(const SimulateArgs& a) {
  // check the numbers before reading any file
  const Integrator integrator = ParseIntegratorFlag(a.integrator);
  RequirePositive(a.dt, "--dt");
  RequireNonNegative(a.duration, "--duration");
  if (a.every < 1) throw UsageError("--every must be at least 1");

  CheckOutputFile("--out", a.out);

  // the body and its world
  const StartingWorld setup = LoadStartingWorld(a.files, a.q, a.qdot, a.world, integrator, a.dt);
  World world = setup.MakeWorld();
  const long expected_steps =
      std::max(1L, CheckRunLimits(a.duration, a.dt, a.every, int(record::Trajectory(world).Columns().size()), a.limits));
  const Energies e0 = world.ComputeEnergies(0);

  // step, recording every Nth state (record::Recorder) and the deepest penetration
  auto trajectory = std::make_shared<record::Trajectory>(world);
  auto recorder = std::make_shared<record::Recorder>(trajectory, a.every);
  recorder->Start(world);
  world.SetRecorder(recorder);
  double max_pen = world.Penetration(0), max_pen_time = 0.0;
  Progress progress(isatty(STDERR_FILENO) == 1);
  const auto start = std::chrono::steady_clock::now();
  bool ok = false;
  try {
    ok = world.RunUntil(a.duration, [&](const World& w) {
      const double pen = w.Penetration(0);
      if (pen > max_pen) {
        max_pen = pen;
        max_pen_time = w.time();
      }
      progress.Update(double(w.steps()) / double(expected_steps), w.time());
    });
  } catch (const Interrupted& e) {
    // Ctrl-C: the rows up to here are the file, and the message says so
    progress.Finish();
    recorder->Finish(world);
    if (a.out.empty()) throw;
    record::WriteTrajectoryCsv(a.out, *trajectory);
    throw Interrupted(std::string(e.what()) + "; wrote its " + std::to_string(trajectory->size()) + " rows to " + a.out);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.Finish();
  // a stopped world keeps its last accepted state; the last state is always recorded
  recorder->Finish(world);
  const World& final_world = world;

  // the trajectory, also when the run stopped: it shows what led there
  if (!a.out.empty()) record::WriteTrajectoryCsv(a.out, *trajectory);

  // the summary: one paragraph, a sentence per line
  const Energies e = final_world.ComputeEnergies(0);
  const Ground& g = setup.options.params.ground;
  const bool three = setup.dim() == 3;
  const std::string name = setup.OnBody([](const auto& body) { return body.name(); });
  const int points = setup.OnBody([](const auto& body) { return body.num_points(); });
  const int modes = setup.OnBody([](const auto& body) { return body.num_modes(); });
  std::ostringstream out;
  out << name << (three ? " (3D)" : "") << ": " << points << " mass points, " << modes << " modes; "
      << IntegratorName(integrator) << " integrator, dt " << Num(a.dt) << "; gravity "
      << (setup.options.params.gravity_on ? "on" : "off") << "; ";
  if (g.enabled) {
    out << (three ? "ground plane" : "ground") << " through y = " << Num(g.point.y()) << " at "
        << Num(a.world.ground_slope_deg) << " deg.\n";
  } else {
    out << "no ground.\n";
  }
  if (!ok)
    out << "The run STOPPED at step " << world.status().step << " (" << StatusCodeName(world.status().code) << ").\n";
  out << "Simulated " << Num(world.time()) << " s in " << world.steps() << " steps: " << Num(wall)
      << " s wall with recording, " << (wall > 0 ? Num(double(world.steps()) / wall) : std::string("-"))
      << " steps/s.\n";
  int contacts = 0;
  if (three) {
    const BodyState<3, double>& s = final_world.state<3>(0);
    const Eigen::Quaterniond& o = s.orientation();
    out << "Final state at t = " << Num(world.time()) << ": t = " << VectorText(s.translation()) << ", orientation (w x y z) = "
        << VectorText(Eigen::Vector4d(o.w(), o.x(), o.y(), o.z())) << ", modes = " << VectorText(s.gamma()) << ",\n"
        << "  v (t-dot, body omega, modes-dot) = " << VectorText(s.qd) << ".\n";
    contacts = int(s.contacts.size());
  } else {
    const BodyState<2, double>& s = final_world.state<2>(0);
    out << "Final state at t = " << Num(world.time()) << ": q = " << VectorText(s.q) << ",\n"
        << "  qdot = " << VectorText(s.qd) << ".\n";
    contacts = int(s.contacts.size());
  }
  out << "Energies at the end: kinetic " << Num(e.kinetic) << ", gravity " << Num(e.gravity) << ", modes "
      << Num(e.modes) << ", ground " << Num(e.ground) << ", springs " << Num(e.springs) << ", total "
      << Num(e.total()) << " (" << Num(e0.total()) << " at the start).\n";
  out << contacts << " point" << (contacts == 1 ? "" : "s")
      << " in contact at the end; max penetration " << Num(max_pen);
  if (max_pen > 0) out << " at t = " << Num(max_pen_time);
  out << ".\n";
  if (!a.out.empty()) {
    out << "Wrote " << trajectory->size() << " rows to " << a.out << ".";
  } else {
    out << "No --out given: nothing written.";
  }
  std::cout << out.str() << std::endl;

  if (!ok) {
    std::cerr << "wobble: simulation stopped: " << world.status().message << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

}  // namespace wobble::app
