#pragma once
// The cgroups of one emulated episode (docs/design.md, "Time: two clocks"): a group sized to
// the board under the `enavi` parent, one child per thread for the per-core speed, removed
// when destroyed. Created by CgroupManager::CreateEpisode (cgroup_manager.h).

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "workers/emulation/board_quota.h"
#include "workers/emulation/cgroup_layout.h"

namespace enavi::emulation {

struct CgroupContext;  // detection result + options, shared by a manager and its groups

/// Limits of one episode besides the CPU quota.
struct EpisodeLimits {
  std::string cpus;               ///< cpuset.cpus list ("0-1"); empty = all of the worker's CPUs
  std::int64_t memory_bytes = 0;  ///< memory limit; 0 = none
};

/// Throttling counters of a group (cpu.stat).
struct CpuStat {
  std::int64_t nr_periods = 0;
  std::int64_t nr_throttled = 0;
  std::int64_t throttled_ns = 0;
};

/// The groups of one episode; removed (tasks of other processes killed, threads of this process
/// moved back home) when destroyed. Move-only.
class EpisodeCgroup {
 public:
  ~EpisodeCgroup();
  EpisodeCgroup(const EpisodeCgroup&) = delete;
  EpisodeCgroup& operator=(const EpisodeCgroup&) = delete;

  const std::string& name() const { return name_; }
  const BoardQuota& quota() const { return quota_; }
  /// The board group in the cpu hierarchy (v2: the unified tree).
  const std::string& cpu_dir() const { return cpu_dir_; }

  /// Moves every thread of process `pid` into the episode's groups (all controllers).
  CgroupStatus AddProcess(pid_t pid);
  /// Gives thread `tid` its own child group with the per-core quota and moves it there. The
  /// thread's process must already be in the episode (AddProcess), v2 requires it.
  CgroupStatus AddThread(pid_t tid);
  /// Gives every thread its own child group: those still directly in the board group and those
  /// that share another thread's group (a thread inherits its creator's group), and removes the
  /// groups of threads that exited. Call after the navstack started its threads and then
  /// periodically (it is a directory read when nothing changed). Returns threads placed.
  int SweepThreads(CgroupStatus* status = nullptr);

  CpuStat ReadCpuStat() const;
  /// Every thread inside the board group and its per-thread groups (cpu hierarchy).
  std::vector<pid_t> Tasks() const;

  /// Kills every task of other processes inside (processes that fork while being killed
  /// included), for up to `timeout_s`; the groups stay. False if tasks remain.
  bool KillTasks(double timeout_s = 5.0);

  /// Kills tasks of other processes still inside, moves threads of this process back to the
  /// worker's own groups, removes the directories. Idempotent; the destructor calls it.
  /// `with_parent`: also the `enavi` parent when no episode is left in it, whether or not its
  /// manager lives (a process that outlived the worker that made the group cleans up after it).
  CgroupStatus Remove(bool with_parent = false);

 private:
  friend class CgroupManager;
  EpisodeCgroup() = default;

  std::shared_ptr<const CgroupContext> context_;
  std::string name_;
  BoardQuota quota_;
  std::string cpu_dir_, cpuset_dir_, memory_dir_;
  bool removed_ = false;
};

}  // namespace enavi::emulation
