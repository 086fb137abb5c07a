#include "wobble/scene/object_runs.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace wobble::scene {

namespace {

// (run, sample) of every sample of the motion, each hand-over once.
std::vector<std::pair<int, int>> Samples(const ObjectRuns& runs) {
  std::vector<std::pair<int, int>> s;
  for (int r = 0; r < int(runs.size()); ++r)
    for (int k = 0; k < runs[r]->size(); ++k) {
      if (k == 0 && !s.empty() && runs[s.back().first]->time(s.back().second) == runs[r]->time(0)) s.pop_back();
      s.emplace_back(r, k);
    }
  return s;
}

// The rigid part of a body's q and q̇: 3 and 3 in 2D (t, θ), 7 and 6 in 3D (t, quaternion | ṫ, ω).
int RigidQ(const record::BodyInfo& b) { return b.num_q - b.num_modes(); }
int RigidV(const record::BodyInfo& b) { return b.num_v - b.num_modes(); }

// The motion's modes by name, first seen first, and each run's column for each of its modes.
struct ModeColumns {
  std::vector<std::string> names;
  std::vector<std::vector<int>> of_run;
  explicit ModeColumns(const ObjectRuns& runs) {
    for (const auto& run : runs) {
      const std::vector<std::string>& coords = run->bodies().at(0).coordinate_names;
      std::vector<int> columns;
      for (size_t c = size_t(RigidQ(run->bodies().at(0))); c < coords.size(); ++c) {
        const auto it = std::find(names.begin(), names.end(), coords[c]);
        columns.push_back(int(it - names.begin()));
        if (it == names.end()) names.push_back(coords[c]);
      }
      of_run.push_back(std::move(columns));
    }
  }
};

// t, q and q̇ of sample k of a run on the motion's modes, and its PD targets on them.
std::vector<double> MappedState(const record::Trajectory& run, int k, const std::vector<int>& columns, int num_modes,
                                Eigen::VectorXd* targets = nullptr) {
  const int rq = RigidQ(run.bodies()[0]), rv = RigidV(run.bodies()[0]);
  const int nq = rq + num_modes, nv = rv + num_modes;
  std::vector<double> row(1 + nq + nv, 0.0);
  row[0] = run.time(k);
  const auto q = run.q(k, 0), qd = run.qd(k, 0);
  for (int i = 0; i < rq; ++i) row[1 + i] = q[i];
  for (int i = 0; i < rv; ++i) row[1 + nq + i] = qd[i];
  for (size_t d = 0; d < columns.size(); ++d) {
    row[1 + rq + columns[d]] = q[rq + int(d)];
    row[1 + nq + rv + columns[d]] = qd[rv + int(d)];
  }
  if (targets) {
    targets->setZero(num_modes);
    for (size_t d = 0; d < columns.size(); ++d) (*targets)[columns[d]] = run.targets(k, 0)[int(d)];
  }
  return row;
}

// The body of the whole motion: the object with every mode any run had, in column order.
template <int Dim>
std::shared_ptr<const BodyModelN<Dim>> MergedModel(const ObjectRuns& runs, const ModeColumns& columns) {
  std::vector<DeformationModeN<Dim>> modes(columns.names.size());
  for (size_t r = 0; r < runs.size(); ++r) {
    const BodyModelN<Dim>& body = *runs[r]->bodies().at(0).ffd<Dim>();
    for (int d = 0; d < body.num_modes(); ++d) modes[size_t(columns.of_run[r][size_t(d)])] = body.modes()[size_t(d)];
  }
  return std::make_shared<const BodyModelN<Dim>>(runs[0]->bodies()[0].ffd<Dim>()->def(), std::move(modes));
}

}  // namespace

record::Trajectory MergeRuns(const ObjectRuns& runs) {
  if (runs.empty()) throw std::invalid_argument("MergeRuns: no runs");
  const ModeColumns columns(runs);
  const int N = int(columns.names.size());
  record::BodyInfo info = runs[0]->bodies()[0];
  const int rq = RigidQ(info), rv = RigidV(info);
  if (info.ffd<3>()) info.set_ffd(MergedModel<3>(runs, columns));
  else info.set_ffd(MergedModel<2>(runs, columns));
  info.coordinate_names.resize(size_t(rq));
  info.coordinate_names.insert(info.coordinate_names.end(), columns.names.begin(), columns.names.end());
  info.velocity_names.resize(size_t(rv));
  for (const std::string& name : columns.names) info.velocity_names.push_back("d" + name);
  info.num_q = rq + N;
  info.num_v = rv + N;
  record::Trajectory merged({info});
  for (const auto& [r, k] : Samples(runs)) {
    const record::Trajectory& run = *runs[r];
    Eigen::VectorXd targets;
    std::vector<double> row = MappedState(run, k, columns.of_run[r], N, &targets);
    row.insert(row.end(), targets.data(), targets.data() + N);
    const Energies e = run.energies(k, 0);
    for (double v : {e.kinetic, e.gravity, e.modes, e.ground, e.springs, e.total(), double(run.contacts(k, 0)),
                     run.penetration(k, 0), run.control_energy(k), double(run.pose(k)), run.violation(k)})
      row.push_back(v);
    merged.AppendRow(row);
  }
  return merged;
}

record::Trajectory OutputTrajectory(const ObjectRuns& runs, int every) {
  if (every < 1) throw std::invalid_argument("OutputTrajectory: every must be at least 1");
  const record::Trajectory merged = MergeRuns(runs);
  record::Trajectory out(merged.bodies());
  for (int k = 0; k < merged.size(); k += every) out.AppendRow(std::vector<double>(merged.Row(k), merged.Row(k) + merged.num_columns()));
  return out;
}

}  // namespace wobble::scene
