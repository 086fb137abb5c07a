// Where the checkout's data and the build's outputs are, for tests, benchmarks and fuzz replays.
//
// The absolute paths are compiled into source_paths.cc alone: every other test, bench and fuzz
// source is then byte-identical in every clone, so a compiler cache shared between clones in
// different folders (ccache's base_dir, set up in the top-level CMakeLists.txt) hits on them.
// A path in a -D definition of each test would make every test a miss in a new clone.
#pragma once

#include <string>

namespace wobble::test_env {

// data/ of the checkout (objects, modes, scripts)
const std::string& DataDir();
// tests/baselines/ of the checkout (render regression images)
const std::string& BaselineDir();
// where a failed render comparison leaves its images (in the build folder)
const std::string& RenderFailureDir();
// the `wobble` command line of this build (app/); built only with WOBBLE_BUILD_APP
const std::string& CliPath();

}  // namespace wobble::test_env
