#include "wobble/script/interpreter.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "wobble/formats/line_reader.h"
#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

using namespace script_detail;

// ---------------------------------------------------------------- the language

const std::vector<CommandInfo>& Interpreter::Commands() {
  static const std::vector<CommandInfo> commands = [] {
    std::vector<CommandInfo> c;
    for (const Command& command : CommandTable()) c.push_back({command.name, command.usage, command.help});
    return c;
  }();
  return commands;
}

const std::vector<std::string>& Interpreter::Parameters() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const Parameter& p : ParameterTable()) n.push_back(p.name);
    return n;
  }();
  return names;
}

std::string Interpreter::Help() {
  std::string text = "commands:\n";
  for (const CommandInfo& c : Commands()) text += "  " + c.usage + "\n      " + c.summary + "\n";
  text += "parameters of set:";
  for (const std::string& p : Parameters()) text += " " + p;
  return text + "\n";
}

std::string Interpreter::Nearest(const std::string& word, const std::vector<std::string>& known) {
  auto lower = [](std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string w = lower(word);
  std::string best;
  size_t best_d = std::string::npos;
  for (const std::string& k0 : known) {
    const std::string k = lower(k0);
    // Levenshtein distance, one row at a time
    std::vector<size_t> row(k.size() + 1);
    for (size_t j = 0; j <= k.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= w.size(); ++i) {
      size_t diag = row[0];
      row[0] = i;
      for (size_t j = 1; j <= k.size(); ++j) {
        const size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (w[i - 1] == k[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    if (row[k.size()] < best_d) {
      best_d = row[k.size()];
      best = k0;
    }
  }
  const size_t limit = std::max<size_t>(2, w.size() / 3);
  return best_d <= limit ? best : "";
}

// ---------------------------------------------------------------- running scripts

Interpreter::Interpreter(std::ostream& out) : state_(std::make_unique<State>(out)) {
  std::ostream* o = &out;
  state_->scene.SetLog([o](const std::string& line) { *o << "  " << line << "\n"; });
}

Interpreter::~Interpreter() = default;

void Interpreter::RunFile(const std::string& path) {
  formats::detail::WithFile(path, [&](std::istream& in) {
    RunStream(in, path, std::filesystem::path(path).parent_path().string());
    return 0;
  });
}

namespace {

// No script line is this long; a stream with no line ends (a binary file, /dev/zero on
// standard input) is refused at its first line instead of being read whole into memory.
constexpr size_t kMaxScriptLine = 65536;

// std::getline with that bound, and refusing a NUL byte (binary input, not a script).
bool ReadScriptLine(std::istream& in, const std::string& name, int number, std::string* line) {
  line->clear();
  std::streambuf* buffer = in.rdbuf();
  for (bool any = false;; any = true) {
    const int c = buffer->sbumpc();
    if (c == std::char_traits<char>::eof()) return any;
    if (c == '\n') return true;
    if (c == '\0') throw formats::ParseError(name, number, "holds a NUL byte: a script is text");
    if (line->size() == kMaxScriptLine)
      throw formats::ParseError(name, number, "is longer than " + std::to_string(kMaxScriptLine) + " characters: a script line is shorter");
    line->push_back(char(c));
  }
}

}  // namespace

void Interpreter::RunStream(std::istream& in, const std::string& name, const std::string& dir) {
  std::string line;
  for (int number = 1; ReadScriptLine(in, name, number, &line); ++number)
    if (!RunLine(line, name, number, dir)) return;
}

bool Interpreter::RunLine(const std::string& line, const std::string& name, int line_number, const std::string& dir) {
  std::istringstream in(line.substr(0, line.find('#')));
  Words words;
  for (std::string w; in >> w;) words.push_back(w);
  if (words.empty()) return true;
  const std::string& word = words[0] == "exit" ? "quit" : words[0];
  const std::vector<Command>& table = CommandTable();
  const auto command = std::find_if(table.begin(), table.end(), [&](const Command& c) { return word == c.name; });
  Context ctx{name, line_number, dir, command == table.end() ? word : command->usage};
  if (command == table.end()) {
    std::vector<std::string> names;
    for (const Command& c : table) names.push_back(c.name);
    ctx.Fail("unknown command '" + word + "'" + DidYouMean(word, names));
  }
  // one exit-code policy (core/errors.h): whatever a command's parts throw leaves here as bad
  // input (ParseError naming this line), a numerical stop (SimulationStopped), Interrupted, or
  // an other failure, every message prefixed with this line
  const std::string here = name + ":" + std::to_string(line_number) + ": ";
  try {
    command->run(*state_, words, ctx);
  } catch (const formats::ParseError& e) {
    if (e.file() == name && e.line() == line_number) throw;
    throw formats::ParseError(name, line_number, e.what());  // a file the line loads: both places
  } catch (const SimulationStopped&) {
    throw;
  } catch (const NumericalStop& e) {
    throw SimulationStopped(here + e.what());
  } catch (const Interrupted& e) {
    throw Interrupted(here + e.what());
  } catch (const std::invalid_argument& e) {  // InputError, LimitExceeded, values that do not fit
    throw formats::ParseError(name, line_number, e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(here + e.what());
  }
  return !state_->quit;
}

void Interpreter::LoadObject(const std::string& path) { LoadObj(*state_, {"load_obj", path}, Context{"", 0, "", ""}); }

void Interpreter::SetProgress(std::function<void(double, double)> progress) { state_->progress = std::move(progress); }
void Interpreter::SetHistoryHook(HistoryHook hook) { state_->history_hook = std::move(hook); }
void Interpreter::SetRenderHook(RenderHook hook) { state_->render_hook = std::move(hook); }
void Interpreter::SetSceneRenderHook(SceneRenderHook hook) { state_->scene_render_hook = std::move(hook); }
void Interpreter::SetMeshReader(formats::MeshReader reader) { state_->mesh_reader = std::move(reader); }

// ---------------------------------------------------------------- state

scene::Scene& Interpreter::scene() { return state_->scene; }
const scene::Scene& Interpreter::scene() const { return state_->scene; }
const BodyModel* Interpreter::body() const { return state_->scene.object().Body<2>().get(); }
const Eigen::VectorXd& Interpreter::q() const { return state_->scene.object().q(); }
const Eigen::VectorXd& Interpreter::qd() const { return state_->scene.object().qd(); }
double Interpreter::time() const { return state_->scene.time(); }
double Interpreter::control_energy() const { return state_->scene.control_energy().consumed; }
const control::PoseGraph& Interpreter::pose_graph() const { return state_->scene.control().graph; }
const WorldOptions& Interpreter::world_options() const { return state_->scene.options(); }
const std::optional<synth::AnnealResult>& Interpreter::last_anneal() const { return state_->anneal; }

synth::Problem Interpreter::SynthesisProblem() const { return script::SynthesisProblem(*state_); }
std::string Interpreter::ReplayScript() const { return script::ReplayScript(*state_); }

}  // namespace wobble::script
