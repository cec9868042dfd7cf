#pragma once
// How a board is emulated on this host (the `enavi calibrate` table): its speed against this
// host's cores from the host calibration, the host CPUs its quota takes and the smallest
// dilation that fits (a board faster than the host needs a dilation of at least its speed).

#include <map>
#include <string>

#include "workers/board/board_profile.h"
#include "workers/board/host_calibration.h"

namespace enavi::emulation {

struct BoardEmulation {
  std::string board;
  int cores = 1;
  double speed_vs_host = 1.0;  ///< board per-core speed / host per-core speed
  double quota_cpus_k1 = 0;    ///< cores x speed: host CPUs the board takes at dilation 1
  double min_dilation = 1.0;   ///< smallest k that fits `host_cpus_free` (and >= speed_vs_host)
  /// Board WCET per task (max job time of the calibration flights on this board), seconds.
  std::map<std::string, double> wcet_s;
  /// The same for the 99th percentile (the max is often one map rebuild).
  std::map<std::string, double> p99_s;
};
/// `host_cpus_free`: host CPUs an emulation may use (e.g. HostCpus - 0.25 for the simulator).
BoardEmulation DescribeBoardEmulation(const board::BoardProfile& board, const board::HostCalibration& host,
                                      double host_cpus_free);

}  // namespace enavi::emulation
