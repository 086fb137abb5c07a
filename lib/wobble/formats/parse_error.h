// The error every wobble input reader throws on bad input.
#pragma once

#include <stdexcept>
#include <string>

namespace wobble::formats {

// Bad input: what() is "FILE:LINE: message" (LINE 0 when the problem is the file as a whole,
// e.g. it cannot be opened or is empty). Lines count from 1, comments and blank lines included.
class ParseError : public std::runtime_error {
 public:
  ParseError(std::string file, int line, const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  // The message alone, without the "FILE:LINE: " prefix.
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  std::string message_;
};

}  // namespace wobble::formats
