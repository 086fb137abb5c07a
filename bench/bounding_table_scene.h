// The bounding-table scene of data/NAME.wob up to (not including) its anneal, and random
// neighbours of its initial pose graph: the trials synth_bench and mpi_bench time.
#pragma once

#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "wobble/script/interpreter.h"
#include "wobble/synth/anneal.h"
#include "support/source_paths.h"

namespace wobble::bench {

// bounding_table (2D) or bounding_table3 (the 3D table, issue 15).
struct BoundingTable {
  explicit BoundingTable(const std::string& name = "bounding_table") : interp(sink) {
    const std::string path = wobble::test_env::DataDir() + "/" + name + ".wob";
    std::ifstream f(path);
    std::string line;
    for (int n = 1; std::getline(f, line); ++n) {
      if (line.rfind("anneal", 0) == 0) break;
      interp.RunLine(line, path, n, wobble::test_env::DataDir());
    }
    problem = interp.SynthesisProblem();
    graph = interp.pose_graph();
  }
  std::ostringstream sink;
  script::Interpreter interp;
  synth::Problem problem;
  control::PoseGraph graph;
};

// n neighbours of `graph` (targets + N(0, 0.1), fixed seed: the same work every run).
inline std::vector<control::PoseGraph> Neighbours(const control::PoseGraph& graph, int n) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal(0.0, 0.1);
  std::vector<control::PoseGraph> out(size_t(n), graph);
  for (control::PoseGraph& g : out)
    for (Eigen::VectorXd& p : g.poses)
      for (int i = 0; i < p.size(); ++i) p[i] += normal(rng);
  return out;
}

}  // namespace wobble::bench
