#include "support/source_paths.h"

namespace wobble::test_env {

const std::string& DataDir() {
  static const std::string dir = WOBBLE_SOURCE_DIR "/data";
  return dir;
}

const std::string& BaselineDir() {
  static const std::string dir = WOBBLE_SOURCE_DIR "/tests/baselines";
  return dir;
}

const std::string& RenderFailureDir() {
  static const std::string dir = WOBBLE_BINARY_DIR "/tests/render_failures";
  return dir;
}

const std::string& CliPath() {
  static const std::string path = WOBBLE_BINARY_DIR "/app/wobble";
  return path;
}

}  // namespace wobble::test_env
