#pragma once
// Detection of the cgroup hierarchy the emulated clock can use (docs/design.md, "Time: two
// clocks"): v2 (unified) or v1 (one hierarchy per controller), and the worker's own group in
// each, under which the `enavi` parent is created. Reads only; changes nothing.

#include <string>

namespace enavi::emulation {

enum class CgroupVersion { kNone, kV1, kV2 };

struct CgroupOptions {
  /// Where the hierarchies are mounted (unit tests point this at a directory of plain files).
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

/// Parses a cpuset list ("0-3,6,8-9") into the number of CPUs; -1 if malformed.
int CountCpuList(const std::string& list);

}  // namespace enavi::emulation
