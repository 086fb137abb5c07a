#include "wobble/core/limits.h"

#include <cmath>
#include <sstream>

#include "wobble/core/errors.h"

namespace wobble {

namespace {
std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

long CheckedCount(double value, long min_count, long max_count, const std::string& what,
                  const std::string& raise_hint) {
  if (!std::isfinite(value)) throw InputError(what + " must be finite, got " + Num(value));
  // Compared as doubles before any conversion: a value past 2^63 never reaches an integer.
  const double rounded = std::round(value);
  if (rounded < double(min_count))
    throw InputError(what + " must be at least " + std::to_string(min_count) + ", got " + Num(value));
  if (rounded > double(max_count))
    throw LimitExceeded(what + " is " + Num(rounded) + ", over the limit of " + std::to_string(max_count) +
                        (raise_hint.empty() ? std::string() : "; " + raise_hint));
  return long(rounded);
}

long RunSteps(double duration, double dt, const Limits& limits, const std::string& hint) {
  if (!std::isfinite(dt) || dt <= 0) throw InputError("dt must be a finite number > 0, got " + Num(dt));
  if (!std::isfinite(duration) || duration < 0)
    throw InputError("the duration must be a finite number >= 0, got " + Num(duration));
  return CheckedCount(duration / dt, 0, limits.max_steps,
                      "the run of " + Num(duration) + " s at dt " + Num(dt) + " in steps", hint);
}

void CheckRecordSize(double values, const Limits& limits, const std::string& hint) {
  const double mb = values * double(sizeof(double)) / (1024.0 * 1024.0);
  if (!(mb <= limits.max_record_mb))
    throw LimitExceeded("the record would keep " + Num(mb) + " MiB of samples, over the limit of " +
                        Num(limits.max_record_mb) + " MiB" + (hint.empty() ? std::string() : "; " + hint));
}

}  // namespace wobble
