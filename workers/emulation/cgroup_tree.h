#pragma once
// The `enavi` tree of groups that a manager and its episode groups share: the context (options,
// detected layout), the names of episode and thread groups, the directories of each, and how
// the tree is created and emptied. Internal to workers/emulation.
//
// Only directories named `enavi` / `ep-<pid>-<start>-<n>` / `t-<tid>` that this code creates
// are ever written, removed, or have their tasks killed.

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "workers/emulation/cgroup_layout.h"

namespace enavi::emulation {

// Everything a manager and its episode groups share: options, detection result, whether the
// tree is a real cgroup filesystem. A directory tree on an ordinary filesystem (how the unit
// tests drive this code without root) gets plain files and no kills.
struct CgroupContext {
  CgroupOptions options;
  CgroupLayout layout;
  bool plain_files = false;  ///< not on a cgroup filesystem (statfs): plain files, no kills
  pid_t owner_pid = 0;
  std::uint64_t owner_start = 0;
  // An episode that outlives its manager removes the parent itself when it is the last one.
  mutable std::atomic<bool> manager_alive{true};
};

/// Episode group names: ep-<pid>-<start>-<n>, the creating worker's pid and start time.
struct EpisodeName {
  pid_t pid = 0;
  std::uint64_t start = 0;
};
std::optional<EpisodeName> ParseEpisodeName(const std::string& name);
/// Whether the worker that created an episode group still runs (same pid, same start time).
bool OwnerAlive(const EpisodeName& e);
/// A thread group's name: t-<tid>.
bool IsThreadDirName(const std::string& name);

/// One directory an episode (or the parent) spans, with the home group of its hierarchy where
/// threads of this process go back to.
struct HierarchyDir {
  std::string dir;
  std::string home;
  bool is_cpu = false;
};
/// The episode's directories in every hierarchy, the cpu one first.
std::vector<HierarchyDir> EpisodeDirs(const CgroupContext& ctx, const std::string& name);
/// The `enavi` parent in every hierarchy, the cpu one first.
std::vector<std::string> ParentDirs(const CgroupContext& ctx);
/// The file listing a group's threads: cgroup.threads (v2) or tasks (v1).
const char* TaskFile(const CgroupContext& ctx);
/// Thread ids in `dir` and its t-* children.
std::vector<pid_t> TasksBelow(const CgroupContext& ctx, const std::string& dir);

/// One value into a control file (a plain-file tree gets a plain file).
CgroupStatus WriteValue(const CgroupContext& ctx, const std::string& path, const std::string& value);
/// Empties an episode's directories without removing them: threads of this process go home,
/// other processes are killed, for up to `attempts` rounds 10 ms apart. True when empty.
bool EmptyEpisodeDirs(const CgroupContext& ctx, const std::vector<HierarchyDir>& dirs, int attempts);
/// Empties and removes an episode's directories: threads of this process go home, other
/// processes are killed (they are the episode's navstack, or orphans of a crashed worker).
CgroupStatus RemoveEpisodeDirs(const CgroupContext& ctx, const std::vector<HierarchyDir>& dirs);
/// Removes a directory this code created (a plain-file tree's files first).
CgroupStatus RemoveDir(const CgroupContext& ctx, const std::string& dir);
/// Creates (if needed) and configures the `enavi` parent in every hierarchy.
CgroupStatus EnsureParents(const CgroupContext& ctx);
/// Removes the parents unless some worker still has episodes in them (it must stay for them).
void RemoveParentsIfUnused(const CgroupContext& ctx);

}  // namespace enavi::emulation
