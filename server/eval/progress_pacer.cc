#include "server/eval/progress_pacer.h"

namespace enavi::server {

bool ProgressPacer::Due(int done, int total, std::chrono::steady_clock::time_point now) {
  const int tenth = total > 0 ? 10 * done / total : 0;
  const bool due = !printed_ || now - last_ >= period_ || tenth > last_tenth_;
  if (due) {
    printed_ = true;
    last_ = now;
    last_tenth_ = tenth;
  }
  return due;
}

}  // namespace enavi::server
