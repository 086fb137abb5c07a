#include "wobble/script/sweep.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <streambuf>

#include "wobble/core/distribute.h"
#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/line_reader.h"
#include "wobble/script/interpreter.h"
#include "wobble/script/variables.h"

namespace wobble::script {
namespace {

// Discards a case's printout: a study keeps its rows.
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, separator)) parts.push_back(part);
  if (!text.empty() && text.back() == separator) parts.push_back("");
  return parts;
}

std::string Number(double v) { return formats::FormatDouble(v); }

std::string Numbers(const Eigen::VectorXd& v) {
  std::string s;
  for (int i = 0; i < v.size(); ++i) s += (i ? " " : "") + Number(v[i]);
  return s;
}

// How many cells a measure takes in a row, and their names.
std::vector<std::string> MeasureColumns(const std::string& measure) {
  if (measure == "state") return {"q", "qd"};
  return {measure};
}

// The script's text, read once (every case expands its own copy).
std::string ReadScript(const std::string& path) {
  return formats::detail::WithFile(path, [&](std::istream& in) {
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  });
}

// The status word of a case that threw, by the exit-code classes of core/errors.h.
std::string CaseStatus(const std::exception& e) {
  if (dynamic_cast<const Interrupted*>(&e)) return "interrupted";
  if (dynamic_cast<const NumericalStop*>(&e)) return "numerical stop";
  if (dynamic_cast<const formats::ParseError*>(&e) || dynamic_cast<const std::invalid_argument*>(&e))
    return "bad input";
  return "failed";
}

// One case: the script with the case's values, then the measures. Never throws: a failure is
// the row's status and message.
std::vector<std::string> RunCase(const SweepOptions& o, const std::string& text, size_t index) {
  const std::vector<std::string>& values = o.plan.cases[index];
  std::vector<std::string> row{std::to_string(index)};
  row.insert(row.end(), values.begin(), values.end());
  size_t width = 0;
  for (const std::string& m : o.measures) width += MeasureColumns(m).size();
  std::vector<std::string> cells(width);
  auto finish = [&](const std::string& status, const std::string& message) {
    row.push_back(status);
    row.insert(row.end(), cells.begin(), cells.end());
    row.push_back(message);
    return row;
  };
  if (InterruptRequested()) return finish(kCaseNotRun, "Ctrl-C before it started");
  std::map<std::string, std::string> vars;
  for (size_t k = 0; k < values.size(); ++k) vars[o.plan.names[k]] = values[k];
  NullBuffer null;
  std::ostream out(&null);
  try {
    Interpreter interp(out);
    interp.scene().limits() = o.limits;
    std::istringstream in(ExpandVariables(text, vars, o.script));
    interp.RunStream(in, o.script, std::filesystem::path(o.script).parent_path().string());
    cells.clear();
    const bool object = interp.scene().object().loaded();
    const control::PoseGraph& graph = interp.pose_graph();
    for (const std::string& m : o.measures) {
      if (m == "cost") {
        if (interp.last_anneal()) cells.push_back(Number(interp.last_anneal()->best_outcome.cost));
        else if (object && !graph.empty()) cells.push_back(Number(synth::RunTrial(interp.SynthesisProblem(), graph).cost));
        else cells.push_back("");
      } else if (m == "trials") {
        cells.push_back(interp.last_anneal() ? std::to_string(interp.last_anneal()->trials) : "0");
      } else if (m == "distance") {
        if (object && !graph.empty() && graph.cyclic) {
          const std::vector<double> d = synth::DistancePerCycle(interp.SynthesisProblem(), graph, o.gait_skip,
                                                                o.gait_cycles);
          double sum = 0.0;
          for (double x : d) sum += x;
          cells.push_back(Number(d.empty() ? 0.0 : sum / double(d.size())));
        } else {
          cells.push_back("");
        }
      } else if (m == "state") {
        cells.push_back(object ? Numbers(interp.q()) : "");
        cells.push_back(object ? Numbers(interp.qd()) : "");
      } else if (m == "time") {
        cells.push_back(Number(interp.time()));
      }
    }
    return finish(kCaseOk, "");
  } catch (const std::exception& e) {
    // the row's width whatever measure failed: every measure's cells empty
    cells.assign(width, "");
    return finish(CaseStatus(e), e.what());
  }
}

Bytes EncodeRow(const std::vector<std::string>& row) {
  ByteWriter w;
  w.Put<std::uint64_t>(row.size());
  for (const std::string& cell : row) w.PutString(cell);
  return w.Take();
}

std::vector<std::string> DecodeRow(const Bytes& bytes) {
  ByteReader in(bytes);
  std::vector<std::string> row(in.Get<std::uint64_t>());
  for (std::string& cell : row) cell = in.GetString();
  return row;
}

}  // namespace

SweepParameter ParseSweepParameter(const std::string& spec) {
  const size_t eq = spec.find('=');
  const std::string expected = "expected NAME=a,b,c or NAME=FROM:TO:N[:log], got '" + spec + "'";
  if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) throw InputError("--param: " + expected);
  SweepParameter p;
  p.name = spec.substr(0, eq);
  const std::string values = spec.substr(eq + 1);
  if (values.find('\n') != std::string::npos) throw InputError("--param " + p.name + ": a value holds a line break");
  if (!IsVariableName(p.name)) throw InputError("--param: '" + p.name + "' is not a variable's name (letters, digits, '_')");
  const std::vector<std::string> range = Split(values, ':');
  if (range.size() == 3 || range.size() == 4) {
    double from, to;
    int n;
    const bool log = range.size() == 4;
    if (!formats::detail::ParseNumber(range[0], &from) || !formats::detail::ParseNumber(range[1], &to) ||
        !formats::detail::ParseInt(range[2], &n) || n < 1 || (log && range[3] != "log") ||
        (log && !(from > 0.0 && to > 0.0)))
      throw InputError("--param " + p.name + ": " + expected + " (N a whole number >= 1; log ranges positive)");
    CheckedCount(n, 1, 10'000'000, "--param " + p.name + "'s values");
    for (int i = 0; i < n; ++i) {
      const double f = n == 1 ? 0.0 : double(i) / double(n - 1);
      // (to − from) i / (n − 1): exact whole numbers for whole steps (seeds 1:200:200)
      const double v = log ? from * std::pow(to / from, f) : from + (to - from) * double(i) / double(n - 1);
      p.values.push_back(i == 0 ? range[0] : i == n - 1 ? range[1] : Number(v));  // the ends as written
    }
    if (n == 1) p.values = {range[0]};
    return p;
  }
  if (range.size() > 1) throw InputError("--param " + p.name + ": " + expected);
  p.values = Split(values, ',');
  for (const std::string& v : p.values)
    if (v.empty()) throw InputError("--param " + p.name + ": an empty value in '" + values + "'");
  return p;
}

SweepPlan GridPlan(const std::vector<SweepParameter>& parameters) {
  SweepPlan plan;
  double count = 1.0;
  for (const SweepParameter& p : parameters) {
    if (std::find(plan.names.begin(), plan.names.end(), p.name) != plan.names.end())
      throw InputError("--param " + p.name + " is given twice");
    plan.names.push_back(p.name);
    count *= double(p.values.size());
  }
  CheckedCount(count, 1, 10'000'000, "the sweep's cases (the product of the parameters' value counts)",
               "split the study into several sweeps");
  plan.cases.assign(size_t(count), {});
  for (size_t c = 0; c < plan.cases.size(); ++c) {
    size_t rest = c;
    std::vector<std::string>& values = plan.cases[c];
    values.resize(parameters.size());
    for (size_t k = parameters.size(); k-- > 0;) {  // the last parameter varies fastest
      values[k] = parameters[k].values[rest % parameters[k].values.size()];
      rest /= parameters[k].values.size();
    }
  }
  return plan;
}

SweepPlan ReadCaseList(const std::string& path) {
  return formats::detail::WithFile(path, [&](std::istream& in) {
    SweepPlan plan;
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
      std::vector<std::string> cells = Split(line, ',');
      for (std::string& cell : cells) {
        const size_t a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
        cell = a == std::string::npos ? "" : cell.substr(a, b - a + 1);
      }
      if (plan.names.empty()) {
        for (const std::string& name : cells)
          if (!IsVariableName(name))
            throw formats::ParseError(path, number, "expected a header of variable names, got '" + name + "'");
        plan.names = cells;
        continue;
      }
      if (cells.size() != plan.names.size())
        throw formats::ParseError(path, number, "expected " + std::to_string(plan.names.size()) +
                                                    " values (one per name of the header), got " +
                                                    std::to_string(cells.size()));
      for (const std::string& cell : cells)
        if (cell.empty()) throw formats::ParseError(path, number, "an empty value");
      plan.cases.push_back(cells);
      if (plan.cases.size() > 10'000'000) throw formats::ParseError(path, number, "more than 10^7 cases");
    }
    if (plan.names.empty()) throw formats::ParseError(path, 0, "expected a header of variable names: the file is empty");
    if (plan.cases.empty()) throw formats::ParseError(path, number, "expected a row of values after the header");
    return plan;
  });
}

const std::vector<std::string>& SweepMeasures() {
  static const std::vector<std::string> measures{"cost", "trials", "distance", "state", "time"};
  return measures;
}

std::vector<std::string> SweepHeader(const SweepOptions& o) {
  std::vector<std::string> header{"case"};
  header.insert(header.end(), o.plan.names.begin(), o.plan.names.end());
  header.push_back("status");
  for (const std::string& m : o.measures)
    for (const std::string& column : MeasureColumns(m)) header.push_back(column);
  header.push_back("message");
  return header;
}

SweepTable RunSweep(const SweepOptions& o) {
  for (const std::string& m : o.measures)
    if (std::find(SweepMeasures().begin(), SweepMeasures().end(), m) == SweepMeasures().end())
      throw InputError("--measure: unknown measure '" + m + "' (cost, trials, distance, state, time)");
  if (o.gait_skip < 0 || o.gait_cycles < 1) throw InputError("--gait: expected SKIP >= 0 and CYCLES >= 1");
  const std::string text = ReadScript(o.script);
  const std::set<std::string> used = VariablesUsed(text, o.script);
  for (const std::string& name : o.plan.names)
    if (!used.count(name))
      throw InputError("parameter '" + name + "' is not used by " + o.script + ": write ${" + name +
                       "} (or ${" + name + ":-DEFAULT}) where its value goes");
  MapOptions map;
  map.threads = o.threads;
  if (o.on_row) map.on_result = [&](size_t i, const Bytes& row) { o.on_row(i, DecodeRow(row)); };
  const std::vector<Bytes> rows = DistributedMap(o.plan.cases.size(), map,
                                                 [&](size_t i) { return EncodeRow(RunCase(o, text, i)); });
  SweepTable table;
  table.header = SweepHeader(o);
  const size_t status_column = 1 + o.plan.names.size();
  for (const Bytes& b : rows) {
    table.rows.push_back(DecodeRow(b));
    if (table.rows.back()[status_column] == kCaseNotRun) ++table.not_run;
  }
  return table;
}

std::string CsvLine(const std::vector<std::string>& cells) {
  std::string line;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i) line += ',';
    const std::string& c = cells[i];
    if (c.find_first_of(",\"\n ") == std::string::npos) {
      line += c;
      continue;
    }
    line += '"';
    for (char ch : c) {
      if (ch == '"') line += '"';
      line += ch == '\n' ? ' ' : ch;
    }
    line += '"';
  }
  return line + '\n';
}

}  // namespace wobble::script
