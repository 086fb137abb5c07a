// formats::ParseTargets<2> and <3> on arbitrary bytes (each input is read as both: one
// of them refuses it at its first line unless it is a 'dimension' line), then what `wobble
// fit` does with a file before fitting (app/fit.cc): CheckMassPointIndices against the 2D or
// 3D table's mass points, the curve or surface target, and the basis of every body point
// (fit/targets.cc). 3D 'mesh' lines get the stand-in reader of fuzz_common.h.
#include <sstream>

#include "fuzz_common.h"
#include "wobble/fit/targets.h"
#include "wobble/formats/target_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const formats::TargetFile targets = formats::ParseTargets(in, "fuzz.tgt");
    // target_file.h: correspondences or a curve, not both; frames only with correspondences
    if (targets.has_correspondences() && targets.has_curve()) std::abort();
    if (targets.is_trajectory() && targets.has_curve()) std::abort();
    for (size_t f = 1; f < targets.frames.size(); ++f)
      if (!(targets.frames[f].time > targets.frames[f - 1].time)) std::abort();
    const BodyModel& table = *fuzz::TableBody();
    formats::CheckMassPointIndices(targets, int(table.def().masses.size()));
    fit::CurveTarget curve;
    for (const formats::TargetCurve& line : targets.polylines) curve.AddPolyline(line.points, line.closed);
    for (const Eigen::Vector2d& p : targets.cloud) curve.AddPoint(p);
    auto basis = [&](const formats::PointTarget& t) {
      const fit::PointBasis b = fit::BasisOf(table, t.mass_point, t.lattice_coords);
      if (!b.b0.allFinite() || !b.B.allFinite()) std::abort();
    };
    for (const formats::PointTarget& t : targets.points) basis(t);
    for (const formats::TargetFrame& f : targets.frames)
      for (const formats::PointTarget& t : f.points) basis(t);
  });
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const formats::TargetFileN<3> targets = formats::ParseTargets<3>(in, "fuzz.tgt", fuzz::StandInMesh);
    if (targets.has_correspondences() && targets.has_curve()) std::abort();
    if (targets.is_trajectory() && targets.has_curve()) std::abort();
    if (!targets.polylines.empty()) std::abort();  // no polylines in 3D
    for (size_t f = 1; f < targets.frames.size(); ++f)
      if (!(targets.frames[f].time > targets.frames[f - 1].time)) std::abort();
    const BodyModelN<3>& table = *fuzz::Table3Body();
    formats::CheckMassPointIndices(targets, table.num_points());
    fit::SurfaceTarget surface;
    if (!targets.mesh.empty()) surface.AddMesh(targets.mesh);
    for (const Eigen::Vector3d& p : targets.cloud) surface.AddPoint(p);
    for (const auto& t : surface.triangles)
      for (int i : t)
        if (i < 0 || i >= int(surface.points.size())) std::abort();
    const Eigen::VectorXd q = Eigen::VectorXd::Zero(table.num_q());
    auto basis = [&](const formats::PointTargetN<3>& t) {
      const fit::PointBasisN<3> b = fit::BasisOf(table, t.mass_point, t.lattice_coords);
      if (!b.b0.allFinite() || !b.B.allFinite() || !fit::PointPosition(b, q).allFinite()) std::abort();
    };
    for (const formats::PointTargetN<3>& t : targets.points) basis(t);
    for (const formats::TargetFrameN<3>& f : targets.frames)
      for (const formats::PointTargetN<3>& t : f.points) basis(t);
  });
  return 0;
}
