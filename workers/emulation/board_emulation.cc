#include "workers/emulation/board_emulation.h"

#include <algorithm>

#include "workers/emulation/board_quota.h"

namespace enavi::emulation {

BoardEmulation DescribeBoardEmulation(const board::BoardProfile& board, const board::HostCalibration& host,
                                      double host_cpus_free) {
  BoardEmulation e;
  e.board = board.id;
  e.cores = board.cores;
  e.speed_vs_host = board::SpeedVsHost(board, host.relative_speed);
  e.quota_cpus_k1 = board.cores * e.speed_vs_host;
  e.min_dilation = host_cpus_free > 0 ? MinimumDilation({board.cores, e.speed_vs_host}, host_cpus_free) : 0.0;
  // A job that took x host seconds takes x / speed on the board.
  for (const auto& [task, t] : host.tasks)
    if (t.jobs > 0) {
      e.wcet_s[task] = t.max_s / e.speed_vs_host;
      e.p99_s[task] = t.p99_s / e.speed_vs_host;
    }
  return e;
}

}  // namespace enavi::emulation
