// Shared by the pipelines tests: the table of data/, worlds in useful states, and an
// evaluation of Eq. 4.2 that does not go through the code under test: the deformed control
// points L_ij + Σ γ_d d^d_ij evaluated by Lattice::Evaluate (Eq. 4.1), then turned and moved
// with a rotation written out here.
#pragma once

#include <cmath>
#include <cstdlib>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include <vtkSmartPointer.h>

#include "pipelines/scene_view.h"
#include "wobble/world/world.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "support/source_paths.h"

namespace wobble::testing {

inline std::shared_ptr<const BodyModel> Table() {
  static auto body = std::make_shared<const BodyModel>(formats::ReadObjectFile(wobble::test_env::DataDir() + "/table.obj"),
                                                       formats::ReadDeformationFile(wobble::test_env::DataDir() + "/table_modes.def"));
  return body;
}

// A source of body 0 of `w`, updated.
template <class S> vtkSmartPointer<S> Source(const World& w) {
  auto s = vtkSmartPointer<S>::New();
  s->SetWorld(&w);
  s->SetBody(0);
  s->Update();
  return s;
}

inline Eigen::VectorXd Vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(int(v.size()));
  int i = 0;
  for (double x : v) out[i++] = x;
  return out;
}

// World position of lattice coordinates st at q, by Lattice::Evaluate on deformed control points.
inline Eigen::Vector2d IndependentWorldPoint(const BodyModel& body, const Eigen::VectorXd& q, const Eigen::Vector2d& st) {
  std::vector<Eigen::Vector2d> control = body.lattice().RestPoints();
  for (size_t c = 0; c < control.size(); ++c)
    for (int d = 0; d < body.num_modes(); ++d) control[c] += q[3 + d] * body.modes()[d].displacement[c];
  const Eigen::Vector2d l = body.lattice().Evaluate(control, st);
  const double c = std::cos(q[2]), s = std::sin(q[2]);
  return Eigen::Vector2d(q[0] + c * l.x() - s * l.y(), q[1] + s * l.x() + c * l.y());
}

// A deformed, turned, moving table in the air (no contacts) on a sloped ground.
inline std::unique_ptr<World> AirborneWorld() {
  WorldOptions o;
  o.params.ground.slope = -10.0 * M_PI / 180.0;
  auto w = std::make_unique<World>(o);
  w->AddBody(Table());
  w->SetState(0, Vec({12, 140, 0.3, 0.05, -0.08, 0.1, 0.07}), Vec({3, -2, 0.4, 0.5, -0.2, 0.1, 0.3}));
  return w;
}

// The demo's drop run until some points touch the ground.
inline std::unique_ptr<World> TouchingWorld() {
  WorldOptions o;
  o.params.ground.slope = -10.0 * M_PI / 180.0;
  auto w = std::make_unique<World>(o);
  w->AddBody(Table());
  w->SetState(0, Vec({0, 50, 0, 0, 0, 0, 0}), Eigen::VectorXd::Zero(7));
  while (w->state<2>(0).contacts.size() < 2 && w->time() < 10) w->Step();
  for (int k = 0; k < 3; ++k) w->Step();  // a little deeper, with anchors that have moved
  return w;
}

inline std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("wobble_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace wobble::testing

// A render test skips only when there is no display to use (DISPLAY unset: VTK 9.1 renders only
// through X). When DISPLAY is set and no X server answers on it, the test fails: a lost X
// connection under a parallel ctest must not pass as a silent skip.
#define REQUIRE_DISPLAY()                                                                      \
  do {                                                                                         \
    const char* display_name = std::getenv("DISPLAY");                                         \
    if (!display_name || !*display_name)                                                       \
      GTEST_SKIP() << "DISPLAY is not set: VTK 9.1 renders only through X (make test runs "    \
                      "ctest under xvfb-run)";                                                 \
    ASSERT_TRUE(::wobble::pipelines::HasDisplay())                                             \
        << "DISPLAY=" << display_name << " is set but no X server answers on it";              \
  } while (false)
