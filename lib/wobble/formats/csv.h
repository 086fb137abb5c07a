// The one CSV writer of wobble: a header line, then rows of numbers in the shortest form that
// reads back to the same double ("nan", "inf", "-inf" spelled out). Files are written
// atomically (atomic_file.h): to FILE.tmp, then renamed over FILE, so a reader never sees half
// a file and a failed write leaves the old file in place.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace wobble::formats {

// Shortest round-trip text of a double.
std::string FormatDouble(double value);

// The CSV text of a table.
std::string CsvText(const std::vector<std::string>& header, const std::vector<std::vector<double>>& rows);

// Throws std::runtime_error (with the path and the reason) when the file cannot be written.
void WriteCsvAtomically(const std::string& path, const std::vector<std::string>& header,
                        const std::vector<std::vector<double>>& rows);
// The same for `num_rows` rows of header.size() numbers each, row k at row(k) (flat storage).
void WriteCsvAtomically(const std::string& path, const std::vector<std::string>& header, int num_rows,
                        const std::function<const double*(int)>& row);

// Checks early that `path` can be written (creating its folder): throws std::runtime_error
// with the reason if not. Leaves nothing behind but the folder.
void CheckWritable(const std::string& path);

}  // namespace wobble::formats
