// The pose-graph targets and their chain rule (adjoint.h), over the dimension; the rollouts'
// cost and gradient are internal/adjoint_sweep.h over each dimension's step piece
// (adjoint_plane.cc, adjoint_space.cc).
#include "wobble/fit/adjoint.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "wobble/fit/internal/adjoint_sweep.h"

namespace wobble::fit {

namespace {

using internal::Pull;
using internal::Seed;
constexpr int kChunk = internal::kAdjointChunk;
using Jet = internal::AdjointJet;

template <int Dim> void CheckGraph(const BodyModelN<Dim>& body, const control::PoseGraph& graph, double width) {
  const std::string invalid = graph.Validate(int(control::ActiveModes(body).size()));
  if (!invalid.empty()) throw std::invalid_argument("pose graph: " + invalid);
  if (!(width > 0.0) || !std::isfinite(width)) throw std::invalid_argument("pose graph: the switch width must be > 0");
}

}  // namespace

template <int Dim>
Eigen::MatrixXd PoseGraphTargets(const BodyModelN<Dim>& body, const control::PoseGraph& graph, double dt, int steps,
                                   double width) {
  CheckGraph(body, graph, width);
  const control::PoseGraphOf<double> c = control::PoseGraphOf<double>::From(body, graph);
  Eigen::MatrixXd targets(body.num_modes(), steps);
  for (int n = 0; n < steps; ++n) targets.col(n) = control::SmoothPoseTargets(c, body.num_modes(), n * dt, width);
  return targets;
}

template <int Dim>
PoseGraphGradient PoseGraphGradientOf(const BodyModelN<Dim>& body, const control::PoseGraph& graph, double dt,
                                       double width, const Eigen::MatrixXd& target_gradient) {
  CheckGraph(body, graph, width);
  const int D = body.num_modes(), steps = int(target_gradient.cols());
  if (target_gradient.rows() != D) throw std::invalid_argument("pose graph gradient: one row per mode needed");
  const int poses = int(graph.poses.size()), entries = poses > 0 ? int(graph.poses[0].size()) : 0;
  const int width_all = poses * entries + int(graph.durations.size());
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(width_all);
  const control::PoseGraphOf<double> plain = control::PoseGraphOf<double>::From(body, graph);
  // forward-mode Jets over the graph's own numbers (a few tens), per step: cheap beside a step
  for (int offset = 0; offset < width_all; offset += kChunk) {
    control::PoseGraphOf<Jet> c;
    c.cyclic = plain.cyclic;
    c.active = plain.active;
    for (int i = 0; i < poses; ++i) {
      VecD<Jet> pose(entries);
      for (int k = 0; k < entries; ++k) pose[k] = Seed(graph.poses[i][k], i * entries + k, offset);
      c.poses.push_back(pose);
    }
    for (size_t i = 0; i < graph.durations.size(); ++i)
      c.durations.push_back(Seed(graph.durations[i], poses * entries + int(i), offset));
    for (int n = 0; n < steps; ++n) {
      const VecD<Jet> target = control::SmoothPoseTargets(c, D, n * dt, width);
      for (int d = 0; d < D; ++d) Pull(target[d], target_gradient(d, n), offset, &grad);
    }
  }
  PoseGraphGradient g;
  for (int i = 0; i < poses; ++i) g.poses.push_back(grad.segment(i * entries, entries));
  for (size_t i = 0; i < graph.durations.size(); ++i) g.durations.push_back(grad[poses * entries + int(i)]);
  return g;
}
template Eigen::MatrixXd PoseGraphTargets<2>(const BodyModelN<2>&, const control::PoseGraph&, double, int, double);
template Eigen::MatrixXd PoseGraphTargets<3>(const BodyModelN<3>&, const control::PoseGraph&, double, int, double);
template PoseGraphGradient PoseGraphGradientOf<2>(const BodyModelN<2>&, const control::PoseGraph&, double, double,
                                                  const Eigen::MatrixXd&);
template PoseGraphGradient PoseGraphGradientOf<3>(const BodyModelN<3>&, const control::PoseGraph&, double, double,
                                                  const Eigen::MatrixXd&);

}  // namespace wobble::fit
