// formats::ParseTargets on arbitrary bytes, then what `wobble fit` does with a file before
// fitting (app/fit.cc): CheckMassPointIndices against the table's mass points, the curve
// target and the basis of every body point (fit/targets.cc).
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
  return 0;
}
