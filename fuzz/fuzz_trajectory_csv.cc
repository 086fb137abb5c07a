// record::ParseTrajectoryCsv on arbitrary bytes for the table body (the CSV `wobble simulate`
// writes and the fits read back).
#include <sstream>

#include "fuzz_common.h"
#include "wobble/record/trajectory_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  static const record::BodyInfo table = record::DescribeFfdBody(fuzz::TableBody());
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const record::ReadTrajectory read = record::ParseTrajectoryCsv(in, "fuzz.csv", {table});
    // the reader promises rows with strictly increasing times
    const record::Trajectory& traj = read.trajectory;
    if (traj.empty()) std::abort();
    for (int k = 0; k < traj.size(); ++k) {
      if (k > 0 && !(traj.time(k) > traj.time(k - 1))) std::abort();
      if (!traj.q(k, 0).allFinite()) std::abort();
      (void)traj.pose(k);  // an int: UBSan reports a pose column that does not fit one
    }
  });
  return 0;
}
