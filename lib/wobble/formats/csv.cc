#include "wobble/formats/csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "wobble/formats/atomic_file.h"

namespace wobble::formats {

std::string FormatDouble(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), value);
  return std::string(buf, res.ptr);
}

std::string CsvText(const std::vector<std::string>& header, const std::vector<std::vector<double>>& rows) {
  std::string text;
  for (size_t i = 0; i < header.size(); ++i) {
    if (i) text += ',';
    text += header[i];
  }
  text += '\n';
  for (const std::vector<double>& row : rows) {
    for (size_t i = 0; i < row.size(); ++i) {
      if (i) text += ',';
      text += FormatDouble(row[i]);
    }
    text += '\n';
  }
  return text;
}

void CheckWritable(const std::string& path) {
  if (OutputsDiscarded()) return;
  CreateParentFolder(path);
  const std::string tmp = TempPathFor(path);
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) throw std::runtime_error(tmp + ": cannot open for writing: " + std::strerror(errno));
  std::fclose(f);
  std::remove(tmp.c_str());
}

namespace {
// Writes the header and then row k = 0..n−1 (row(k) gives its numbers and their count).
void WriteTable(const std::string& path, const std::vector<std::string>& header, int n,
                const std::function<std::pair<const double*, size_t>(int)>& row) {
  WriteFileAtomically(path, [&](const std::string& tmp) {
    WriteWithStdio(tmp, [&](std::FILE* f) {
      std::string line;
      for (size_t i = 0; i < header.size(); ++i) {
        if (i) line += ',';
        line += header[i];
      }
      line += '\n';
      bool ok = std::fputs(line.c_str(), f) >= 0;
      for (int k = 0; k < n && ok; ++k) {  // a line at a time: long runs stay small in memory
        const auto [values, count] = row(k);
        line.clear();
        for (size_t i = 0; i < count; ++i) {
          if (i) line += ',';
          line += FormatDouble(values[i]);
        }
        line += '\n';
        ok = std::fputs(line.c_str(), f) >= 0;
      }
      return ok;
    });
  });
}
}  // namespace

void WriteCsvAtomically(const std::string& path, const std::vector<std::string>& header,
                        const std::vector<std::vector<double>>& rows) {
  WriteTable(path, header, int(rows.size()), [&](int k) { return std::make_pair(rows[size_t(k)].data(), rows[size_t(k)].size()); });
}

void WriteCsvAtomically(const std::string& path, const std::vector<std::string>& header, int num_rows,
                        const std::function<const double*(int)>& row) {
  WriteTable(path, header, num_rows, [&](int k) { return std::make_pair(row(k), header.size()); });
}

}  // namespace wobble::formats
