#pragma once
// Progress on a terminal is a bar redrawn in place; in a log (CI, a pipe, a file) it is lines,
// and a 10-minute run must not show one line at its end. The pacer says when the next line is
// due: every `period`, or as soon as another tenth of the work is done, whichever comes first.

#include <chrono>

namespace enavi::server {

/// The period of progress lines on a non-terminal (`enavi eval`, `enavi status --watch`,
/// `enavi fly`).
inline constexpr std::chrono::seconds kProgressLinePeriod{10};

class ProgressPacer {
 public:
  explicit ProgressPacer(std::chrono::steady_clock::duration period = kProgressLinePeriod) : period_(period) {}

  /// True when a line is due at `now` with `done` of `total` finished (total 0: unknown, time
  /// only). The first call is always due; a true answer counts as the line printed.
  bool Due(int done, int total, std::chrono::steady_clock::time_point now);

 private:
  std::chrono::steady_clock::duration period_;
  bool printed_ = false;
  std::chrono::steady_clock::time_point last_;
  int last_tenth_ = 0;
};

}  // namespace enavi::server
