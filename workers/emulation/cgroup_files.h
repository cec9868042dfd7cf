#pragma once
// File-system helpers of the cgroup code (detection, the enavi tree, episode groups): paths,
// small reads of control files and one-value writes. Internal to workers/emulation.

#include <sys/types.h>

#include <set>
#include <string>
#include <vector>

#include "workers/emulation/cgroup_layout.h"

namespace enavi::emulation::cgroupfs {

std::string Join(const std::string& dir, const std::string& name);
/// Joins a mount point and a cgroup path from /proc/self/cgroup ("/" is the mount itself).
std::string MountPlusPath(const std::string& mount, const std::string& path);
bool Exists(const std::string& path);
bool IsDir(const std::string& path);
bool ReadFile(const std::string& path, std::string* out);
/// Without trailing white space and newlines and leading blanks.
std::string Trim(std::string s);
/// The file's content trimmed; empty when it cannot be read.
std::string ReadTrimmed(const std::string& path);
/// Names of the subdirectories of `dir` (unordered); empty when it cannot be read.
std::vector<std::string> Subdirs(const std::string& dir);
/// The ids in a cgroup task file (cgroup.procs, cgroup.threads, tasks).
std::vector<pid_t> ReadPids(const std::string& path);
/// The white-space separated words of `s`.
std::set<std::string> Words(const std::string& s);
/// Writes `value` with one write() (cgroup files take one value per write). `create` makes a
/// missing file (a tree on an ordinary filesystem, as the unit tests use, holds plain files).
CgroupStatus WriteValue(const std::string& path, const std::string& value, bool create);

}  // namespace enavi::emulation::cgroupfs
