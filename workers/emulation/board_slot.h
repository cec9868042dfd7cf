#pragma once
// A board emulated on this host for one episode (docs/design.md, "Time: two clocks"): its speed
// against this host's cores (host calibration, moved by the speed probe), the dilation k, the
// quotas and the episode's cgroups, admitted against the host's free CPUs. What runs inside is
// the caller's: our navstack process (EmulatedNavLink) or a user's ROS stack (the ROS bridge).
//
// quota = cores x speed / k for the board group, speed / k for each thread's group,
// speed = board per-core speed / host per-core speed (board_quota.h).

#include <map>
#include <memory>
#include <string>

#include "workers/board/board_profile.h"
#include "workers/emulation/board_quota.h"
#include "workers/emulation/cgroup_manager.h"
#include "workers/emulation/emulation_options.h"

namespace enavi::emulation {

class BoardSlot {
 public:
  /// Measures this host's speed, opens the cgroup hierarchy (reaping groups of dead workers),
  /// picks the dilation (`dilation` <= 0: the smallest multiple of 0.25 at which the board fits
  /// the host's free CPUs) and creates the episode's groups. Throws std::invalid_argument when
  /// this host cannot emulate the board: no valid host calibration, no writable cgroup
  /// hierarchy, admission refused, a requested dilation below the board's speed against the host.
  BoardSlot(const board::BoardProfile& board, double dilation, const EmulationOptions& emulation);
  /// Removes the episode's groups (killing what is left inside) and the `enavi` parent if unused.
  ~BoardSlot();
  BoardSlot(const BoardSlot&) = delete;
  BoardSlot& operator=(const BoardSlot&) = delete;

  /// Board core speed / host core speed, > 0 (above 1 the dilation is at least as large).
  double speed() const { return speed_; }
  /// Wall seconds per sim second.
  double dilation() const { return dilation_; }
  const BoardQuota& quota() const { return quota_; }
  EpisodeCgroup& group() { return *group_; }
  const CgroupManager& manager() const { return *manager_; }
  /// How the numbers were produced, for the result's notes (emulation.speed, .dilation, .cgroup, ...).
  const std::map<std::string, std::string>& notes() const { return notes_; }

  /// Removes the groups now (idempotent; the destructor calls it). Returns why a removal
  /// failed, empty if it did not.
  std::string Release();

 private:
  double HostSpeedNow(const board::HostCalibration& cal, const EmulationOptions& emulation);

  double speed_ = 1.0, dilation_ = 1.0;
  BoardQuota quota_;
  std::unique_ptr<CgroupManager> manager_;
  std::unique_ptr<EpisodeCgroup> group_;
  std::map<std::string, std::string> notes_;
};

}  // namespace enavi::emulation
