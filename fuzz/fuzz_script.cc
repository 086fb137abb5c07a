// script::Interpreter::RunStream on arbitrary bytes: every command, scene commands and the
// session scripts of scene::SessionScript included. Input files resolve against data/ (the
// script's folder); output files land in a private temporary folder, the working directory.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <streambuf>
#include <vector>

#include "fuzz_common.h"

namespace {

namespace fs = std::filesystem;

// The harness's own stop: a script asked for more steps than one input may take.
struct WorkBudgetSpent {};

// The scene's limits for one run, and the harness's budget for every run of one input, in
// table-steps: 300 steps of a body of the table's 11 mass points with the thesis integrator,
// fewer for a larger body or a dearer integrator. Under ASan and coverage a table-step costs
// about 0.14-0.19 ms, so a budget of 300 keeps every input's stepping under about 60 ms: the interpreter's
// paths are what this target explores (fuzz_world_step covers long and wild stepping). A run
// the budget cannot afford is refused by the scene's own limit, set before every line to what
// is left (which fuzzes that check too).
constexpr long kMaxStepsPerRun = 4000;
constexpr double kMaxRecordMbPerRun = 64;
constexpr double kMaxTableStepsPerInput = 300;

// What one step of the script's character costs, in table-steps: its mass points over the
// table's 11 (1 point without one: scenes of linear bodies step a few points per body), times
// the integrator's cost per point relative to the thesis integrator in 2D. Measured in this
// build, 200 steps of the table (2D) and of table3 (3D, 27 points), best of three, in ms:
//          thesis  symplectic  RK4  implicit  variational
//   2D       37        33       69     125        234
//   3D       65        93      196     444        622
double StepCost(const wobble::script::Interpreter& interp) {
  static constexpr double kPerPoint[2][5] = {{1.0, 1.0, 1.9, 3.4, 6.3}, {0.7, 1.0, 2.2, 4.9, 6.9}};
  int dim = 2;
  long points = 1;
  const wobble::scene::FfdObject& object = interp.scene().object();
  if (object.loaded()) {
    try {
      dim = object.dim();
      points = std::max(1, dim == 3 ? object.Body<3>()->num_points() : object.Body<2>()->num_points());
    } catch (const std::exception&) {
    }
  }
  int column = 0;
  switch (interp.scene().options().integrator) {
    case wobble::Integrator::kThesis: column = 0; break;
    case wobble::Integrator::kSymplecticEuler: column = 1; break;
    case wobble::Integrator::kRK4: column = 2; break;
    case wobble::Integrator::kImplicitEuler: column = 3; break;
    case wobble::Integrator::kVariational: column = 4; break;
  }
  return kPerPoint[dim == 3 ? 1 : 0][column] * double(points) / 11.0;
}

// Discards what the interpreter prints.
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

// The working directory of this process, /tmp/wobble_fuzz_script_PID: created once, emptied
// after every input. libFuzzer's jobs do not always exit through atexit, so each process
// first removes the folders of processes that are gone.
const fs::path& PrivateFolder() {
  static const fs::path folder = [] {
    const std::string prefix = "wobble_fuzz_script_";
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator("/tmp", ec)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(prefix, 0) != 0) continue;
      const long pid = std::atol(name.c_str() + prefix.size());
      if (pid > 0 && kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
    }
    const fs::path dir = "/tmp/" + prefix + std::to_string(getpid());
    fs::create_directories(dir);
    fs::current_path(dir);
    // a plain copy: atexit runs this after the static path below is destroyed
    static char to_remove[256];
    std::snprintf(to_remove, sizeof to_remove, "%s", dir.c_str());
    std::atexit([] { std::error_code ec; fs::remove_all(to_remove, ec); });
    return dir;
  }();
  return folder;
}

void EmptyFolder(const fs::path& dir) {
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) fs::remove_all(e.path(), ec);
}

bool AsNumber(const std::string& word, double* v) {
  const char* first = word.data();
  if (!word.empty() && *first == '+') ++first;
  const auto [end, ec] = std::from_chars(first, word.data() + word.size(), *v);
  return ec == std::errc() && end == word.data() + word.size();
}

// Whether the harness runs this script at all. Paths: no word may start with '/' or hold
// "..", so nothing is read outside data/ or written outside the private folder. Work is
// bounded by the scene's own limits (set small in LLVMFuzzerTestOneInput, so they get fuzzed
// too), which a script could raise: `set max_steps`, `set max_record_mb` and `set threads`
// are not run. A linear body's grid and levels cost their cube before any step is taken.
bool Acceptable(const std::string& text) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream in(line);
    std::vector<std::string> w;
    for (std::string word; in >> word;) w.push_back(word);
    for (const std::string& word : w)
      if (word[0] == '/' || word.find("..") != std::string::npos) return false;
    if (w.empty()) continue;
    if (w[0] == "set" && w.size() >= 2 && (w[1] == "max_steps" || w[1] == "max_record_mb" || w[1] == "threads"))
      return false;
    if (w[0] == "linear")
      for (size_t i = 1; i + 1 < w.size(); ++i) {
        double v;
        if ((w[i] == "grid" || w[i] == "levels") && AsNumber(w[i + 1], &v) && v > 8) return false;
      }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  const std::string text = fuzz::AsText(data, size);
  if (!Acceptable(text)) return 0;
  const fs::path& folder = PrivateFolder();
  NullBuffer null;
  std::ostream out(&null);
  double spent = 0;  // table-steps (StepCost)
  double last_fraction = 2.0;
  try {
    fuzz::IgnoringExpectedErrors([&] {
      script::Interpreter interp(out);
      interp.scene().limits().max_steps = kMaxStepsPerRun;
      interp.scene().limits().max_record_mb = kMaxRecordMbPerRun;
      // Runs report their fraction done after step 1 (1/steps) and every 64 steps; a new run
      // starts over with a smaller fraction. Synthesis reports per iteration (counted alike).
      interp.SetProgress([&](double fraction, double) {
        if (fraction > 0 && fraction < last_fraction) {
          spent += std::min(1.0 / fraction, 1e9) * StepCost(interp);
          if (spent > kMaxTableStepsPerInput) throw WorkBudgetSpent{};
        }
        last_fraction = fraction;
      });
      // Interpreter::RunStream's loop, with the budget left as each line's step limit: a run,
      // a gait or a synthesis the budget cannot afford is refused by the scene's own check.
      std::istringstream in(text);
      int number = 0;
      for (std::string line; std::getline(in, line);) {
        const double affordable = (kMaxTableStepsPerInput - spent) / StepCost(interp);
        interp.scene().limits().max_steps = long(std::clamp(affordable, 1.0, double(kMaxStepsPerRun)));
        if (!interp.RunLine(line, "fuzz.wob", ++number, fuzz::kDataDir)) break;
      }
    });
  } catch (const WorkBudgetSpent&) {
  }
  EmptyFolder(folder);
  return 0;
}
