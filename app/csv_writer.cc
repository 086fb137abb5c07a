#include "csv_writer.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "wobble/formats/atomic_file.h"

namespace wobble::app {

std::string FormatDouble(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), value);
  return std::string(buf, res.ptr);
}

void CheckWritable(const std::string& path) {
  formats::CreateParentFolder(path);
  const std::string tmp = formats::TempPathFor(path);
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) throw std::runtime_error(tmp + ": cannot open for writing: " + std::strerror(errno));
  std::fclose(f);
  std::remove(tmp.c_str());
}

void WriteCsvAtomically(const std::string& path, const std::vector<std::string>& header,
                        const std::vector<std::vector<double>>& rows) {
  formats::WriteFileAtomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "w");
    if (!f) throw std::runtime_error(tmp + ": cannot open for writing: " + std::strerror(errno));
    std::string line;
    for (size_t i = 0; i < header.size(); ++i) {
      if (i) line += ',';
      line += header[i];
    }
    line += '\n';
    bool ok = std::fputs(line.c_str(), f) >= 0;
    char buf[64];
    for (const std::vector<double>& row : rows) {
      line.clear();
      for (size_t i = 0; i < row.size(); ++i) {
        if (i) line += ',';
        if (std::isfinite(row[i])) {
          const auto res = std::to_chars(buf, buf + sizeof(buf), row[i]);
          line.append(buf, res.ptr);
        } else {
          line += FormatDouble(row[i]);
        }
      }
      line += '\n';
      ok = ok && std::fputs(line.c_str(), f) >= 0;
    }
    const int saved_errno = errno;
    ok = (std::fclose(f) == 0) && ok;
    if (!ok) throw std::runtime_error(tmp + ": " + std::strerror(saved_errno));
  });
}

}  // namespace wobble::app

