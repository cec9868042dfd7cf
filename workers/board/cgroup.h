#pragma once
// cgroup control for the emulated clock (docs/design.md, "Time: two clocks"): one `enavi` parent group, one
// group per episode under it sized to the board, one child per thread for the per-core speed,
// admission against the host's free CPU, RAII removal and reaping of groups left by crashed
// workers. Only directories named `enavi` / `ep-<pid>-<start>-<n>` / `t-<tid>` that this code
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

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "workers/board/board_quota.h"

namespace enavi::board {

enum class CgroupVersion { kNone, kV1, kV2 };

struct CgroupContext;  // detection result + options, shared by a manager and its groups

struct CgroupOptions {
  /// Where the hierarchies are mounted. Tests point this at a fake directory tree.
  std::string root = "/sys/fs/cgroup";
  /// The worker's own membership ("id:controllers:path" lines); injectable for tests.
  std::string self_cgroup_file = "/proc/self/cgroup";
  /// Serialises admission and parent creation/removal among workers of one host.
  std::string lock_file = "/run/lock/enavi-cgroup.lock";
  std::string parent_name = "enavi";
  bool use_cpuset = true;  ///< require and configure cpuset (cpus, mems)
  bool use_memory = true;  ///< require and configure the memory controller
  /// Weight of the `enavi` parent against its siblings (v2 cpu.weight, [1, 10000]; v1
  /// cpu.shares = weight x 1024 / 100). A quota is only a ceiling; the weight makes it close to
  /// a floor when the host is busy with other work, which the fidelity of the emulation needs:
  /// each busy login session is an autogroup of weight 1024, and at weight 1000 (shares 10240)
  /// a 1.4-CPU board lost ~7 % of its quota on this host to four busy sessions.
  int parent_cpu_weight = 10000;
  /// Host CPUs that admission keeps free for the (unthrottled) simulator.
  double host_reserve_cpus = 0.25;
};

/// Which hierarchy the emulation can use, and where.
struct CgroupLayout {
  CgroupVersion version = CgroupVersion::kNone;
  /// Directories in which the `enavi` parent is (to be) created: the worker's own cgroup in
  /// each hierarchy. For v2 all three are the same directory; unused controllers are empty.
  std::string cpu_base;
  std::string cpuset_base;
  std::string memory_base;
  /// Why no hierarchy is usable (version kNone): which path is missing or not writable, and why.
  std::string problem;
};

/// Finds a usable hierarchy without changing anything: v2 when the worker's own v2 cgroup has
/// cpu (+ cpuset, + memory as required) in cgroup.subtree_control and is writable, else v1
/// when the cpu (+ cpuset, + memory) hierarchies are mounted and writable, else kNone with a
/// message naming each missing or unwritable path.
CgroupLayout DetectCgroups(const CgroupOptions& options = {});

/// Outcome of a cgroup operation that can fail for expected reasons.
struct CgroupStatus {
  bool ok = true;
  std::string message;
};

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

class CgroupManager;

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
  /// Gives every thread still directly in the board group its own child group (threads that
  /// the navstack created after AddProcess inherit their creator's group), and removes the
  /// groups of threads that exited. Call after the navstack started its threads and then
  /// periodically (it is a directory read when nothing changed). Returns threads placed.
  int SweepThreads(CgroupStatus* status = nullptr);

  CpuStat ReadCpuStat() const;

  /// Kills tasks of other processes still inside, moves threads of this process back to the
  /// worker's own groups, removes the directories. Idempotent; the destructor calls it.
  CgroupStatus Remove();

 private:
  friend class CgroupManager;
  EpisodeCgroup() = default;

  std::shared_ptr<const CgroupContext> context_;
  std::string name_;
  BoardQuota quota_;
  std::string cpu_dir_, cpuset_dir_, memory_dir_;
  bool removed_ = false;
};

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

/// Parses a cpuset list ("0-3,6,8-9") into the number of CPUs; -1 if malformed.
int CountCpuList(const std::string& list);

}  // namespace enavi::board
