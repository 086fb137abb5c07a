// Writes a table of numbers as CSV, atomically (wobble/io/atomic_file.h): to FILE.tmp, then renamed
// over FILE, so that a reader never sees half a file. Numbers are written in the shortest
// form that reads back to the same double.
#pragma once

#include <string>
#include <vector>

#include "wobble/formats/atomic_file.h"

namespace wobble::app {

// Throws std::runtime_error (with the path and the reason) when the file cannot be written.
void WriteCsvAtomically(const std::string& path, const std::vector<std::string>& header,
                        const std::vector<std::vector<double>>& rows);

// Checks early that `path` can be written (creating its folder): throws std::runtime_error
// with the reason if not. Leaves nothing behind but the folder.
void CheckWritable(const std::string& path);

// Shortest round-trip text of a double ("nan"/"inf" spelled out; never expected here).
std::string FormatDouble(double value);

}  // namespace wobble::app

namespace wobble::app {
using formats::WriteTextAtomically;  // JSON results and reports: lib/wobble/io/atomic_file.h
}  // namespace wobble::app
