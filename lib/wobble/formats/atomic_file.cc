#include "wobble/formats/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace wobble::formats {

std::string TempPathFor(const std::string& path) { return path + ".tmp"; }

void CreateParentFolder(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;  // a file that does not exist yet is no error here
  if (fs::is_directory(target, ec)) throw std::runtime_error(path + ": is a directory");
  if (!target.has_parent_path()) return;  // the working directory
  fs::create_directories(target.parent_path(), ec);
  if (ec) throw std::runtime_error(path + ": cannot create its folder: " + ec.message());
}

void WriteFileAtomically(const std::string& path, const std::function<void(const std::string& temp_path)>& write) {
  namespace fs = std::filesystem;
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

void WriteTextAtomically(const std::string& path, const std::string& text) {
  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw std::runtime_error(std::string("cannot open ") + tmp + ": " + std::strerror(errno));
    bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    const int saved_errno = errno;
    ok = (std::fclose(f) == 0) && ok;
    if (!ok) throw std::runtime_error(std::strerror(saved_errno));
  });
}

}  // namespace wobble::formats
