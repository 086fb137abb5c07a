#include "wobble/formats/parse_error.h"

#include <utility>

namespace wobble::formats {

ParseError::ParseError(std::string file, int line, const std::string& message)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + message),
      file_(std::move(file)),
      line_(line),
      message_(message) {}

}  // namespace wobble::formats
