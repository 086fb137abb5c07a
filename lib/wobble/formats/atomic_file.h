// Atomic file output: every file wobble writes goes to a temporary file in the same folder
// (FILE.tmp) and is renamed over FILE only once it is complete, so a reader never sees half
// a file and a failed write leaves any earlier FILE untouched.
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace wobble::formats {

// Under MPI every rank runs the same command, and only rank 0 keeps files: the app calls
// DiscardOutputs() on the others, and every writer and formats::CheckWritable there then does nothing
// (two ranks writing, or probing, the same FILE.tmp would spoil each other's file).
void DiscardOutputs();
bool OutputsDiscarded();

// The temporary name used for `path`: "path.tmp", in the same folder (rename stays atomic).
std::string TempPathFor(const std::string& path);

// What `path` is when it exists and is not a regular file ("a directory", "a FIFO", "a
// character device", ...), following symbolic links; empty for a regular file or nothing.
std::string NonRegularKind(const std::string& path);

// Creates the folder of `path` if needed. Throws std::runtime_error naming the path and reason,
// also when `path` exists and is not a regular file, or its temporary file is a FIFO: wobble
// replaces only regular files, and opening a FIFO for writing blocks until a reader comes.
void CreateParentFolder(const std::string& path);

// Opens `temp_path` for writing, lets `fill` write it (false: a write fell short) and closes
// it. Throws std::runtime_error with the system's reason for the first failure, the close
// included (a full disk often shows only there).
void WriteWithStdio(const std::string& temp_path, const std::function<bool(std::FILE*)>& fill);

// Writes `path` atomically: creates its folder, checks that the temporary file can be
// created (a clear error with the system's reason if not), calls write(temp_path) to fill
// it, and renames it over `path`. When `write` throws, or leaves no file behind, or the
// rename fails, the temporary file is removed, `path` is left as it was, and a
// std::runtime_error naming `path` and the reason is thrown.
void WriteFileAtomically(const std::string& path, const std::function<void(const std::string& temp_path)>& write);

// The common case: `text` becomes the whole file (JSON, CSV, scripts), by the function above.
void WriteTextAtomically(const std::string& path, const std::string& text);

}  // namespace wobble::formats
