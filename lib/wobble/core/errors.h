// The three kinds of failure every wobble entry point tells apart, and the exit codes the
// command maps them to (app/main.cc, one table for every subcommand and the interpreter):
//   2  bad input of any kind: a file (formats::ParseError, "FILE:LINE: ..."), a command-line
//      value, a script line, or a request over a stated limit (InputError, LimitExceeded);
//   3  a numerical stop: the simulation or a fit could not go on with finite numbers
//      (NumericalStop; the world's WorldStatus says which and where);
//   1  anything else (a write that failed, a bug);
// and 130 when Ctrl-C stopped the work (Interrupted; 128 + SIGINT, the shell's convention).
#pragma once

#include <stdexcept>
#include <string>

namespace wobble {

// Bad input that is not a file's line: a value out of range, modes that do not fit, ...
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A request that would exceed one of the stated work or memory limits (core/limits.h); the
// message names the limit and how to raise it. Refused before the work starts.
class LimitExceeded : public InputError {
 public:
  using InputError::InputError;
};

// The numbers stopped being finite (or a solver gave up on them): the cause is in the message.
class NumericalStop : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Ctrl-C (core/interrupt.h): the work stopped cleanly; the message says where.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace wobble
