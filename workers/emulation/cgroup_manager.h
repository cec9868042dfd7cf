#pragma once
// cgroup control for the emulated clock (docs/design.md, "Time: two clocks"): one `enavi`
// parent group, one group per episode under it sized to the board, one child per thread for the
// per-core speed, admission against the host's free CPU, RAII removal and reaping of groups left
// by crashed workers. Only directories named `enavi` / `ep-<pid>-<start>-<n>` / `t-<tid>` that this code
// creates are ever written, removed, or have their tasks killed.
//
// Layout (v1, one hierarchy per controller; v2: the same names in the unified tree):
//   <cpu base>/enavi/ep-<pid>-<start>-<n>/          cpu.cfs_quota_us = board quota
//   <cpu base>/enavi/ep-<pid>-<start>-<n>/t-<tid>/  cpu.cfs_quota_us = core quota (v2: threaded)
//   <cpuset base>/enavi/ep-.../                     cpuset.cpus, cpuset.mems
//   <memory base>/enavi/ep-.../                     memory.limit_in_bytes (v2 memory.max)
// <base> is the worker's own cgroup in that hierarchy (from /proc/self/cgroup): the groups nest
// under whatever limits the worker itself runs with (systemd / container delegation).
// <pid> and <start> (its start time, /proc/<pid>/stat field 22) name the worker that created
// the group; when that process no longer exists the group is stale.
//
// This header: the `enavi` parent of a worker, reaping of stale groups, and admission against
// the host's free CPU (CgroupManager). Detection: cgroup_layout.h; one episode's groups:
// episode_cgroup.h.

#include <memory>
#include <string>
#include <vector>

#include "workers/emulation/board_quota.h"
#include "workers/emulation/cgroup_layout.h"
#include "workers/emulation/episode_cgroup.h"

namespace enavi::emulation {

/// Owns the `enavi` parent of this worker. Open() detects the hierarchy, creates the parent
/// and reaps stale episode groups; CreateEpisode() admits and creates one episode's groups.
class CgroupManager {
 public:
  struct OpenResult {
    std::unique_ptr<CgroupManager> manager;
    std::string error;  ///< why the emulation is unavailable (the caller refuses --clock emulated)
    std::vector<std::string> reaped;  ///< stale episode groups removed at start (to log)
    std::string reap_errors;          ///< stale groups that could not be removed, and why
    bool ok() const { return manager != nullptr; }
  };
  static OpenResult Open(const CgroupOptions& options = {});

  /// Removes the parent group if no episode (of any worker) is left in it.
  ~CgroupManager();
  CgroupManager(const CgroupManager&) = delete;
  CgroupManager& operator=(const CgroupManager&) = delete;

  const CgroupLayout& layout() const;

  /// Removes episode groups whose creating worker no longer exists, killing what is left in
  /// them. Returns the names removed. Open() calls it.
  std::vector<std::string> ReapStale(std::string* errors = nullptr);

  /// CPUs the worker may use (its cpuset, else its affinity).
  double HostCpus() const;
  /// Host CPUs held by live episode groups under the parent (sum of board quotas / periods).
  double ReservedCpus() const;

  struct CreateResult {
    std::unique_ptr<EpisodeCgroup> group;
    std::string refusal;  ///< admission refused or creation failed: the reason
    bool ok() const { return group != nullptr; }
  };
  /// Admits the board if HostCpus() - host_reserve_cpus - ReservedCpus() >= quota.BoardCpus(),
  /// then creates and configures its groups. The reservation lasts as long as the group.
  CreateResult CreateEpisode(const BoardQuota& quota, const EpisodeLimits& limits = {});

 private:
  explicit CgroupManager(std::shared_ptr<const CgroupContext> context);
  std::shared_ptr<const CgroupContext> context_;
};

}  // namespace enavi::emulation
