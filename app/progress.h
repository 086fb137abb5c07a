// A one-line progress bar on stderr for long runs (shown only on a terminal: callers pass
// isatty(STDERR_FILENO)), shared by the subcommands.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace wobble::app {

// Redrawn only when the percentage changes; the simulated time (or what `label` names) is
// shown beside it.
class Progress {
 public:
  explicit Progress(bool enabled, const char* label = "t") : enabled_(enabled), label_(label) {}
  void Update(double fraction, double t) {
    if (!enabled_) return;
    const int percent = int(std::floor(100.0 * std::min(1.0, std::max(0.0, fraction))));
    if (percent == last_) return;
    last_ = percent;
    const int width = 40, filled = percent * width / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%%  %s = %-10.4g", std::string(filled, '#').c_str(),
                 std::string(width - filled, '.').c_str(), percent, label_, t);
    std::fflush(stderr);
  }
  void Finish() {
    if (enabled_ && last_ >= 0) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  const char* label_;
  int last_ = -1;
};

}  // namespace wobble::app
