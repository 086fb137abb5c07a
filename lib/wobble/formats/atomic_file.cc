#include "wobble/formats/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace wobble::formats {

std::string TempPathFor(const std::string& path) { return path + ".tmp"; }

std::string NonRegularKind(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;  // a file that does not exist (or cannot be looked at) has no kind here
  switch (fs::status(path, ec).type()) {
    case fs::file_type::directory: return "a directory";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::socket: return "a socket";
    case fs::file_type::unknown: return "a special file";
    default: return "";  // regular, or not there
  }
}

void CreateParentFolder(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  // "out/", "." or "dir/..": a folder's name, never a file's (found by fuzz_script: `output out/`
  // passed the check, which wrote its probe inside the folder, and failed only at the write)
  const std::string name = target.filename().string();
  if (name.empty() || name == "." || name == "..")
    throw std::runtime_error(path + ": names a folder, not a file");
  const std::string kind = NonRegularKind(path);
  if (kind == "a directory") throw std::runtime_error(path + ": is a directory");
  if (!kind.empty()) throw std::runtime_error(path + ": is " + kind + ", not a regular file; wobble writes only regular files");
  // the temporary file is opened for writing before the rename: a FIFO there would block the
  // open forever (any other kind fails at the open or the write, with the system's reason)
  const std::string tmp = TempPathFor(path);
  if (NonRegularKind(tmp) == "a FIFO")
    throw std::runtime_error(path + ": its temporary file " + tmp + " is a FIFO, not a regular file; remove it");
  if (!target.has_parent_path()) return;  // the working directory
  fs::create_directories(target.parent_path(), ec);
  if (ec) throw std::runtime_error(path + ": cannot create its folder: " + ec.message());
}

namespace {
std::atomic<bool> outputs_discarded{false};
}  // namespace

void DiscardOutputs() { outputs_discarded = true; }
bool OutputsDiscarded() { return outputs_discarded; }

void WriteFileAtomically(const std::string& path, const std::function<void(const std::string& temp_path)>& write) {
  namespace fs = std::filesystem;
  if (OutputsDiscarded()) return;
  CreateParentFolder(path);
  const std::string tmp = TempPathFor(path);
  // open the temporary file ourselves first: writers report "cannot open" less clearly
  std::FILE* probe = std::fopen(tmp.c_str(), "wb");
  if (!probe) throw std::runtime_error(path + ": cannot open " + tmp + " for writing: " + std::strerror(errno));
  std::fclose(probe);
  try {
    write(tmp);
  } catch (const std::exception& e) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": write failed: " + e.what());
  }
  std::error_code ec;
  if (!fs::exists(tmp, ec)) throw std::runtime_error(path + ": write failed: " + tmp + " was not written");
  fs::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename " + tmp + " to it: " + ec.message());
  }
}

void WriteWithStdio(const std::string& tmp, const std::function<bool(std::FILE*)>& fill) {
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot open " + tmp + ": " + std::strerror(errno));
  errno = 0;
  bool ok = false;
  try {
    ok = fill(f) && std::fflush(f) == 0;
  } catch (...) {
    std::fclose(f);
    throw;
  }
  int error = ok ? 0 : errno;  // the first failure's reason, before fclose can change errno
  if (std::fclose(f) != 0 && error == 0) error = errno;
  if (!ok || error != 0) throw std::runtime_error(tmp + ": " + (error ? std::strerror(error) : "short write"));
}

void WriteTextAtomically(const std::string& path, const std::string& text) {
  WriteFileAtomically(path, [&](const std::string& tmp) {
    WriteWithStdio(tmp, [&](std::FILE* f) { return std::fwrite(text.data(), 1, text.size(), f) == text.size(); });
  });
}

}  // namespace wobble::formats
