#include "workers/emulation/board_quota.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace enavi::emulation {
namespace {

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

}  // namespace

BoardQuota ComputeBoardQuota(const BoardCpu& board, const QuotaOptions& options) {
  if (board.cores < 1) {
    throw std::invalid_argument("board quota: cores must be >= 1, got " + std::to_string(board.cores));
  }
  if (!(board.core_speed > 0.0) || !std::isfinite(board.core_speed)) {
    throw std::invalid_argument("board quota: core_speed (board per-core speed / host per-core "
                                "speed) must be > 0, got " + Num(board.core_speed));
  }
  if (!(options.dilation >= 1.0) || !std::isfinite(options.dilation)) {
    throw std::invalid_argument("board quota: dilation must be >= 1, got " + Num(options.dilation));
  }
  if (options.dilation < board.core_speed) {
    throw std::invalid_argument("board quota: dilation must be >= the board's core speed " +
                                Num(board.core_speed) + " x a host core's (a thread gets speed / "
                                "dilation of a host core, at most one), got " + Num(options.dilation));
  }
  if (options.period_us < 1000 || options.period_us > 1'000'000) {
    throw std::invalid_argument("board quota: period_us must be in [1000, 1000000], got " +
                                std::to_string(options.period_us));
  }
  BoardQuota q;
  q.cores = board.cores;
  q.core_speed = board.core_speed;
  q.dilation = options.dilation;
  q.period_us = options.period_us;
  const double core_cpus = board.core_speed / options.dilation;
  q.core_quota_us = std::llround(core_cpus * static_cast<double>(options.period_us));
  q.board_quota_us = std::llround(core_cpus * board.cores * static_cast<double>(options.period_us));
  if (q.core_quota_us < kMinQuotaUs) {
    const double min_period = std::ceil(kMinQuotaUs / core_cpus);
    throw std::invalid_argument("board quota: per-thread quota " + std::to_string(q.core_quota_us) +
                                " us (speed " + Num(board.core_speed) + " / dilation " +
                                Num(options.dilation) + " x period " +
                                std::to_string(options.period_us) + " us) is below the kernel "
                                "minimum of 1000 us; use period_us >= " + Num(min_period));
  }
  return q;
}

double MinimumDilation(const BoardCpu& board, double host_cpus_free) {
  if (!(host_cpus_free > 0.0)) {
    throw std::invalid_argument("MinimumDilation: host_cpus_free must be > 0, got " +
                                Num(host_cpus_free));
  }
  const double need = std::max(board.cores * board.core_speed / host_cpus_free, board.core_speed);
  return std::max(1.0, std::ceil(need * 4.0 - 1e-9) / 4.0);
}

double ExpectedSlowdown(const BoardQuota& quota, int threads, double host_cpus) {
  if (threads < 1) throw std::invalid_argument("ExpectedSlowdown: threads must be >= 1");
  const double rate = std::min({quota.CoreCpus(), quota.BoardCpus() / threads,
                                host_cpus / threads, 1.0});
  return 1.0 / rate;
}

double HostToBoardPercent(double host_percent, const BoardQuota& quota) {
  return host_percent / quota.CoreCpus();
}

}  // namespace enavi::emulation
