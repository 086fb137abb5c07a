#include "sweep.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>

#include "progress.h"
#include "wobble/core/distribute.h"
#include "wobble/core/interrupt.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/formats/line_reader.h"
#include "wobble/script/sweep.h"

#ifdef WOBBLE_HAVE_PIPELINES
#include "pipelines/charts.h"
#include "pipelines/scene_view.h"
#endif

namespace wobble::app {

CLI::App* AddSweepCommand(CLI::App* app, SweepArgs* a) {
  CLI::App* cmd = app->add_subcommand("sweep", "A study: the script once per case of a grid or list of its ${variables}, "
                                               "one results table (threads, or MPI ranks under mpirun)");
  cmd->add_option("script", a->script, "Script whose ${NAME} (or ${NAME:-DEFAULT}) words the cases fill")
      ->required()
      ->type_name("SCRIPT");
  cmd->add_option("--param", a->params, "NAME=a,b,c | NAME=FROM:TO:N | NAME=FROM:TO:N:log; several make a grid")
      ->type_name("SPEC");
  cmd->add_option("--list", a->list, "CSV of cases instead: a header of names, a row of values per case")
      ->type_name("FILE");
  cmd->add_option("--measure", a->measures, "Comma list: cost, trials, distance, state, time")->capture_default_str();
  cmd->add_option("--plot", a->plot, "The measure plotted over the first one or two parameters (default: the first)");
  cmd->add_option("--gait", a->gait, "SKIP,CYCLES of the distance measure (periods skipped, periods averaged)")
      ->capture_default_str();
  cmd->add_option("--threads", a->threads, "Threads per process (0: every core, shared by the ranks of a node)")
      ->capture_default_str();
  cmd->add_option("--out", a->out, "Output folder: sweep.csv, sweep.png")->capture_default_str();
  AddLimitFlags(cmd, &a->limits);
  cmd->footer(
      "Examples:\n"
      "  wobble sweep data/sweep_hop.wob --param seed=1:8:8 --param pose_step=0.05,0.1,0.2 --measure cost,distance\n"
      "  mpirun -np 4 wobble sweep data/sweep_hop.wob --param seed=1:100:100 --out out/seeds\n"
      "Rows reach OUT/sweep.csv.partial as cases finish (a run that dies keeps them); OUT/sweep.csv,\n"
      "in case order, replaces it at the end.");
  return cmd;
}

namespace {

// The finished rows as they come (completion order), flushed one by one, so a run that is
// killed keeps them; sweep.csv, in case order, replaces this file at the end.
class PartialRows {
 public:
  PartialRows(const std::string& path, const std::vector<std::string>& header) : path_(path) {
    if (formats::OutputsDiscarded()) return;  // MPI ranks other than 0
    file_ = std::fopen(path.c_str(), "w");
    if (!file_) throw std::runtime_error(path + ": cannot open for writing: " + std::strerror(errno));
    Write(header);
  }
  ~PartialRows() {
    if (file_) std::fclose(file_);
  }
  void Write(const std::vector<std::string>& row) {
    if (!file_) return;
    const std::string line = script::CsvLine(row);
    if (std::fputs(line.c_str(), file_) < 0 || std::fflush(file_) != 0) {
      std::cerr << "wobble sweep: " << path_ << ": " << std::strerror(errno) << " (the table is still written at the end)\n";
      std::fclose(file_);
      file_ = nullptr;
    }
  }
  void Remove() {
    if (file_) std::fclose(file_);
    file_ = nullptr;
    if (!formats::OutputsDiscarded()) std::remove(path_.c_str());
  }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

// mpirun ends every rank with SIGTERM on Ctrl-C and when one of them dies (so does a batch
// system at its time limit): rank 0 then says how many rows are on disk, and where, before it goes. The text is
// prepared after every row, so the handler only writes it (async-signal-safe).
char stop_note[1024];
std::atomic<size_t> stop_note_length{0};

void OnTerminate(int) {
  const size_t n = stop_note_length.load();
  if (n > 0 && write(STDERR_FILENO, stop_note, n) < 0) _exit(143);
  _exit(143);  // 128 + SIGTERM
}

void PrepareStopNote(size_t finished, size_t total, const std::string& partial) {
  const std::string text = "\nwobble sweep: stopped by SIGTERM (mpirun sends it to every rank on Ctrl-C and when a rank "
                           "dies, which it names); " +
                           std::to_string(finished) + " of " + std::to_string(total) + " finished rows are in " +
                           partial + "\n";
  stop_note_length = 0;
  const size_t n = std::min(text.size(), sizeof stop_note);
  std::memcpy(stop_note, text.data(), n);
  stop_note_length = n;
}

bool AsNumber(const std::string& s, double* v) { return formats::detail::ParseNumber(s, v); }

// The measure over the first parameter, a line per value of the second.
void PlotSweep(const script::SweepOptions& o, const script::SweepTable& t, const std::string& measure,
               const std::string& png) {
#ifdef WOBBLE_HAVE_PIPELINES
  const auto column = std::find(t.header.begin(), t.header.end(), measure) - t.header.begin();
  const size_t status = 1 + o.plan.names.size();
  const std::string& first = o.plan.names[0];
  // x: the first parameter's value when every one is a number, else its index among the values
  std::vector<std::string> distinct;
  bool numeric = true, whole = true;
  for (const auto& values : o.plan.cases) {
    double v;
    numeric = numeric && AsNumber(values[0], &v);
    whole = whole && numeric && v == std::floor(v);
    if (std::find(distinct.begin(), distinct.end(), values[0]) == distinct.end()) distinct.push_back(values[0]);
  }
  std::map<std::string, pipelines::ChartSeries> lines;
  std::vector<std::string> order;
  for (const auto& row : t.rows) {
    double x, y;
    const std::string& value = row[1];
    if (!numeric) x = double(std::find(distinct.begin(), distinct.end(), value) - distinct.begin());
    else AsNumber(value, &x);
    const std::string key = o.plan.names.size() > 1 ? o.plan.names[1] + " = " + row[2] : measure;
    if (!lines.count(key)) order.push_back(key), lines[key].name = key;
    if (row[status] != script::kCaseOk || !AsNumber(row[size_t(column)], &y)) continue;  // a gap
    lines[key].x.push_back(x);
    lines[key].y.push_back(y);
  }
  pipelines::ChartSpec spec;
  spec.title = measure + " over " + first + (o.plan.names.size() > 1 ? " and " + o.plan.names[1] : "") + " (" +
               std::to_string(t.rows.size()) + " cases)";
  spec.x_title = numeric ? first : first + " (index of its value)";
  spec.y_title = measure;
  spec.integer_x = whole || !numeric;  // seeds, counts, value indices
  double lo = INFINITY, hi = -INFINITY;
  for (const std::string& key : order) {
    pipelines::ChartSeries s = lines[key];
    s.points = s.x.size() < 3;
    for (double y : s.y) lo = std::min(lo, y), hi = std::max(hi, y);
    if (!s.x.empty()) spec.series.push_back(s);
  }
  if (spec.series.empty()) {
    std::cout << "plot: no case gave a number for " << measure << ": " << png << " not drawn\n";
    return;
  }
  spec.log_y = lo > 0.0 && hi / lo > 1e3;
  pipelines::WriteChart(spec, png, "");
  std::cout << "plot: " << png << "\n";
#else
  (void)o, (void)t, (void)measure, (void)png;
#endif
}

}  // namespace

int RunSweep(const SweepArgs& a) {
  CheckLimitFlags(a.limits);
  if (a.threads < 0 || a.threads > kMaxThreads) throw UsageError("--threads must be in [0, 256]");
  script::SweepOptions o;
  o.script = a.script;
  o.threads = a.threads;
  o.limits = a.limits;
  if (!a.list.empty() && !a.params.empty()) throw UsageError("give --param or --list, not both");
  if (a.list.empty() && a.params.empty()) throw UsageError("a sweep needs cases: --param NAME=VALUES or --list FILE");
  if (!a.list.empty()) {
    o.plan = script::ReadCaseList(a.list);
  } else {
    std::vector<script::SweepParameter> parameters;
    for (const std::string& spec : a.params) parameters.push_back(script::ParseSweepParameter(spec));
    o.plan = script::GridPlan(parameters);
  }
  std::istringstream measures(a.measures);
  for (std::string m; std::getline(measures, m, ',');)
    if (!m.empty()) o.measures.push_back(m);
  {
    const size_t comma = a.gait.find(',');
    if (comma == std::string::npos || !formats::detail::ParseInt(a.gait.substr(0, comma), &o.gait_skip) ||
        !formats::detail::ParseInt(a.gait.substr(comma + 1), &o.gait_cycles))
      throw UsageError("--gait: expected SKIP,CYCLES, got '" + a.gait + "'");
  }
  std::string plotted = a.plot;
  if (plotted.empty())
    for (const std::string& m : o.measures)
      if (m != "state") {
        plotted = m;
        break;
      }
  if (!plotted.empty() && (plotted == "state" || std::find(o.measures.begin(), o.measures.end(), plotted) == o.measures.end()))
    throw UsageError("--plot: '" + plotted + "' is not one of the numeric measures asked for (--measure " + a.measures + ")");
  CheckOutputFolder(a.out);
  const std::filesystem::path out(a.out);
  const std::string table_path = (out / "sweep.csv").string();
  // the files it will write, before any case runs (a FIFO left at one would block the run)
  for (const std::string& file : {table_path, table_path + ".partial", (out / "sweep.png").string()})
    CheckOutputFile("--out", file);

  const size_t n = o.plan.cases.size();
  const Distributor& where = CurrentDistributor();
  std::cout << "sweep: " << n << " cases of " << a.script << " on " << where.ranks() << " rank"
            << (where.ranks() > 1 ? "s" : "") << "\n";
  PartialRows partial(table_path + ".partial", script::SweepHeader(o));  // (only on rank 0)
  Progress progress(isatty(STDERR_FILENO) == 1 && IsOutputRank(), "cases");
  size_t finished = 0;
  const std::string partial_path = table_path + ".partial";
  if (IsOutputRank()) {
    PrepareStopNote(0, n, partial_path);
    std::signal(SIGTERM, OnTerminate);
  }
  o.on_row = [&](size_t, const std::vector<std::string>& row) {
    partial.Write(row);
    ++finished;
    progress.Update(double(finished) / double(n), double(finished));
    PrepareStopNote(finished, n, partial_path);
  };
  const auto start = std::chrono::steady_clock::now();
  const script::SweepTable table = script::RunSweep(o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.Finish();

  std::string text = script::CsvLine(table.header);
  std::map<std::string, int> statuses;
  const size_t status = 1 + o.plan.names.size();
  for (const auto& row : table.rows) {
    text += script::CsvLine(row);
    ++statuses[row[status]];
  }
  formats::WriteTextAtomically(table_path, text);
  std::signal(SIGTERM, SIG_DFL);
  partial.Remove();
  std::cout << "sweep: " << n << " cases in " << seconds << " s:";
  for (const auto& [word, count] : statuses) std::cout << " " << count << " " << word;
  std::cout << "\ntable: " << table_path << "\n";
  if (table.not_run > 0)
    throw Interrupted("the sweep stopped by Ctrl-C: " + std::to_string(n - table.not_run) + " of " + std::to_string(n) +
                      " cases ran; " + table_path + " holds them (the rest are marked '" + script::kCaseNotRun + "')");
#ifdef WOBBLE_HAVE_PIPELINES
  if (!plotted.empty() && IsOutputRank()) {
    if (pipelines::HasDisplay()) PlotSweep(o, table, plotted, (out / "sweep.png").string());
    else std::cout << "no X display: plot skipped (run under xvfb-run -a)\n";
  }
#endif
  return kExitOk;
}

}  // namespace wobble::app
