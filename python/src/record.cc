// The one recorder (record/trajectory.h) from Python: simulate() runs a world and returns the
// Trajectory it recorded. Its samples are one flat row-major block, so the arrays Python gets
// (array, column, time, q, qd) are read-only views of it, no copy: a trajectory from Python
// never grows again, so the views stay valid while any of them lives.
#include "support.h"

#include "wobble/core/errors.h"
#include "wobble/core/limits.h"
#include "wobble/record/trajectory.h"
#include "wobble/record/trajectory_csv.h"

namespace wobble::python {
namespace {

using record::Trajectory;
using TrajectoryPtr = std::shared_ptr<Trajectory>;

// A read-only view of rows x cols numbers from column `first` on (row stride: the width).
py::array View(const TrajectoryPtr& t, int first, int cols, bool vector) {
  const py::ssize_t rows = t->size(), width = t->num_columns(), d = sizeof(double);
  static const double kNone = 0.0;  // a pointer for views of no rows
  const double* data = rows > 0 ? t->Row(0) + first : &kNone;
  py::array out = vector ? py::array(py::dtype::of<double>(), {rows}, {width * d}, data, py::cast(t))
                         : py::array(py::dtype::of<double>(), {rows, py::ssize_t(cols)}, {width * d, d}, data, py::cast(t));
  py::detail::array_proxy(out.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return out;
}

int ColumnOrThrow(const Trajectory& t, const std::string& name) {
  const int c = t.Column(name);
  if (c < 0) {
    std::string names;
    for (const std::string& n : t.Columns()) names += (names.empty() ? "" : " ") + n;
    throw InputError("no column '" + name + "' (columns: " + names + ")");
  }
  return c;
}

// The first column of body b's q (or q̇): its first coordinate's name, prefixed "NAME." when
// the trajectory has more than one body (record/trajectory.h).
int StateColumn(const Trajectory& t, int body, bool velocity) {
  if (body < 0 || body >= t.num_bodies())
    throw InputError("body " + std::to_string(body) + ": the trajectory has " + std::to_string(t.num_bodies()) + " bodies");
  const record::BodyInfo& b = t.bodies()[body];
  const std::string prefix = t.num_bodies() > 1 ? b.name + "." : "";
  return ColumnOrThrow(t, prefix + (velocity ? b.velocity_names.at(0) : b.coordinate_names.at(0)));
}

// Runs `world` for `duration` with a Recorder (every `every`-th step, or `fps` samples per
// second), within the limits of core/limits.h; returns what it recorded. A stopped world raises
// SimulationStopped, whose .trajectory holds the samples up to the stop.
TrajectoryPtr Simulate(World& world, double duration, int every, double fps, long max_steps, double max_record_mb) {
  if (!(duration >= 0)) throw InputError("duration must be at least 0");
  if (every < 1) throw InputError("every must be at least 1");
  if (!(fps >= 0)) throw InputError("fps must be at least 0 (0: sample every `every` steps)");
  const Limits limits{max_steps, max_record_mb};
  const long steps = RunSteps(duration, world.options().dt, limits, "raise max_steps");
  auto trajectory = std::make_shared<Trajectory>(world);
  const double samples = fps > 0 ? duration * fps + 2 : double(steps) / every + 2;
  CheckRecordSize(samples * trajectory->num_columns(), limits, "raise max_record_mb, or sample less often");
  auto recorder = fps > 0 ? std::make_shared<record::Recorder>(trajectory, fps, world.time())
                          : std::make_shared<record::Recorder>(trajectory, every);
  recorder->Start(world);
  world.SetRecorder(recorder);
  try {
    RunWorld(world, world.time() + duration, -1);
  } catch (py::error_already_set& e) {
    // stopped: the status with the samples that led there
    recorder->Finish(world);
    world.SetRecorder(nullptr);
    e.value().attr("trajectory") = trajectory;
    throw;
  } catch (...) {  // Ctrl-C
    world.SetRecorder(nullptr);
    throw;
  }
  recorder->Finish(world);
  world.SetRecorder(nullptr);  // the trajectory never grows again: its views stay valid
  return trajectory;
}

}  // namespace

void BindRecord(py::module_& m) {
  py::class_<Trajectory, TrajectoryPtr>(
      m, "Trajectory",
      "What a run leaves behind: one row per sample of t, every body's q, q̇, PD targets, energy\n"
      "terms, contacts and penetration, then control_energy, pose and violation (columns).\n"
      "The arrays are read-only views of the samples, not copies.")
      .def("__len__", &Trajectory::size)
      .def_property_readonly("columns", &Trajectory::Columns)
      .def_property_readonly("num_bodies", &Trajectory::num_bodies)
      .def_property_readonly(
          "array", [](const TrajectoryPtr& t) { return View(t, 0, t->num_columns(), false); },
          "(samples, columns): every number")
      .def_property_readonly(
          "time", [](const TrajectoryPtr& t) { return View(t, 0, 1, true); }, "(samples,)")
      .def(
          "column", [](const TrajectoryPtr& t, const std::string& name) { return View(t, ColumnOrThrow(*t, name), 1, true); },
          py::arg("name"), "(samples,) one column by name, e.g. 'kinetic', 'ty', 'contacts'")
      .def(
          "q",
          [](const TrajectoryPtr& t, int body) { return View(t, StateColumn(*t, body, false), t->bodies()[body].num_q, false); },
          py::arg("body") = 0, "(samples, num_q) the body's q")
      .def(
          "qd",
          [](const TrajectoryPtr& t, int body) { return View(t, StateColumn(*t, body, true), t->bodies()[body].num_v, false); },
          py::arg("body") = 0, "(samples, num_v) the body's q̇ (num_q, but 6 + D for a 3D FFD body: ṫ, body ω, γ̇)")
      .def(
          "write_csv", [](const Trajectory& t, const std::string& path) { record::WriteTrajectoryCsv(path, t); },
          py::arg("path"), "Writes the CSV of `wobble simulate` (through a temporary file: never a truncated one).")
      .def("__repr__", [](const Trajectory& t) {
        return "<Trajectory: " + std::to_string(t.size()) + " samples of " + std::to_string(t.num_columns()) + " columns>";
      });

  m.def("simulate", &Simulate, py::arg("world"), py::arg("duration"), py::kw_only(), py::arg("every") = 1,
        py::arg("fps") = 0.0, py::arg("max_steps") = Limits().max_steps, py::arg("max_record_mb") = Limits().max_record_mb,
        "Runs the world for `duration` seconds and returns the Trajectory recorded: a sample every\n"
        "`every` steps, or `fps` per second (film frames); the last state always. LimitExceeded\n"
        "for runs past max_steps or records past max_record_mb; SimulationStopped (with\n"
        ".trajectory) when the world stops.");
  m.def(
      "read_trajectory_csv",
      [](const std::string& path, std::shared_ptr<BodyModel> body) {
        record::ReadTrajectory read = record::ReadTrajectoryCsv(path, {record::DescribeFfdBody(body)});
        return std::make_shared<Trajectory>(std::move(read.trajectory));
      },
      py::arg("path"), py::arg("body"), "Reads a trajectory CSV of one FFD body (wobble simulate's).");
}

}  // namespace wobble::python
