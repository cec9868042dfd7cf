#include "workers/emulation/cgroup_layout.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "workers/emulation/cgroup_files.h"

namespace enavi::emulation {
namespace {

using cgroupfs::Exists;
using cgroupfs::Join;
using cgroupfs::MountPlusPath;
using cgroupfs::ReadTrimmed;
using cgroupfs::Subdirs;
using cgroupfs::Trim;
using cgroupfs::Words;

std::string WritableProblem(const std::string& dir) {
  struct stat st{};
  if (stat(dir.c_str(), &st) != 0) {
    if (errno == ENOENT) return dir + " does not exist";
    return "cannot access " + dir + " as uid " + std::to_string(geteuid()) + " (" +
           std::strerror(errno) + ")";
  }
  if (!S_ISDIR(st.st_mode)) return dir + " is not a directory";
  if (access(dir.c_str(), W_OK) == 0) return {};
  if (errno == EROFS) return dir + " is on a read-only mount (remount it rw)";
  return dir + " is not writable by uid " + std::to_string(geteuid()) + " (" +
         std::strerror(errno) + "; creating cgroups needs root or a delegated subtree)";
}

// /proc/self/cgroup: controller name -> path; "" key for the v2 line "0::/path".
std::map<std::string, std::string> ParseMembership(const std::string& file) {
  std::map<std::string, std::string> out;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    const auto c1 = line.find(':');
    const auto c2 = c1 == std::string::npos ? c1 : line.find(':', c1 + 1);
    if (c2 == std::string::npos) continue;
    const std::string controllers = line.substr(c1 + 1, c2 - c1 - 1);
    const std::string path = line.substr(c2 + 1);
    if (controllers.empty()) {
      out[""] = path;
      continue;
    }
    std::stringstream ss(controllers);
    std::string c;
    while (std::getline(ss, c, ',')) out[c] = path;
  }
  return out;
}

}  // namespace

int CountCpuList(const std::string& list) {
  const std::string s = Trim(list);
  if (s.empty()) return 0;
  int count = 0;
  std::stringstream ss(s);
  std::string range;
  while (std::getline(ss, range, ',')) {
    unsigned a = 0, b = 0;
    int consumed = 0;
    if (std::sscanf(range.c_str(), "%u-%u%n", &a, &b, &consumed) == 2 &&
        consumed == static_cast<int>(range.size()) && b >= a) {
      count += static_cast<int>(b - a + 1);
    } else if (std::sscanf(range.c_str(), "%u%n", &a, &consumed) == 1 &&
               consumed == static_cast<int>(range.size())) {
      count += 1;
    } else {
      return -1;
    }
  }
  return count;
}

CgroupLayout DetectCgroups(const CgroupOptions& options) {
  CgroupLayout layout;
  std::vector<std::string> problems;
  const auto membership = ParseMembership(options.self_cgroup_file);
  if (membership.empty()) {
    problems.push_back("cannot read the worker's cgroup membership from " + options.self_cgroup_file);
  }

  // v2: the unified tree at <root> (pure v2) or <root>/unified (hybrid).
  std::string v2_root;
  for (const std::string& candidate : {options.root, Join(options.root, "unified")}) {
    if (Exists(Join(candidate, "cgroup.controllers"))) {
      v2_root = candidate;
      break;
    }
  }
  if (v2_root.empty()) {
    problems.push_back("cgroup v2: no unified hierarchy at " + options.root + " or " +
                       Join(options.root, "unified"));
  } else if (!membership.count("")) {
    problems.push_back("cgroup v2: no '0::' line in " + options.self_cgroup_file);
  } else {
    const std::string base = MountPlusPath(v2_root, membership.at(""));
    const std::string subtree_file = Join(base, "cgroup.subtree_control");
    const std::set<std::string> enabled = Words(ReadTrimmed(subtree_file));
    std::vector<std::string> needed{"cpu"};
    if (options.use_cpuset) needed.push_back("cpuset");
    if (options.use_memory) needed.push_back("memory");
    std::string missing;
    for (const std::string& c : needed) {
      if (!enabled.count(c)) missing += (missing.empty() ? "" : " ") + c;
    }
    if (!missing.empty()) {
      problems.push_back("cgroup v2 at " + v2_root + ": controller(s) '" + missing +
                         "' not enabled in " + subtree_file + " (enabled: '" +
                         ReadTrimmed(subtree_file) + "')");
    } else if (std::string p = WritableProblem(base); !p.empty()) {
      problems.push_back("cgroup v2: " + p);
    } else {
      layout.version = CgroupVersion::kV2;
      layout.cpu_base = base;
      if (options.use_cpuset) layout.cpuset_base = base;
      if (options.use_memory) layout.memory_base = base;
      return layout;
    }
  }

  // v1: one hierarchy per controller, found by its control files.
  std::map<std::string, std::string> mounts;  // controller -> mount dir
  const std::map<std::string, std::string> marker = {
      {"cpu", "cpu.cfs_quota_us"}, {"cpuset", "cpuset.cpus"}, {"memory", "memory.limit_in_bytes"}};
  std::vector<std::string> subdirs = Subdirs(options.root);
  std::sort(subdirs.begin(), subdirs.end());
  for (const std::string& name : subdirs) {
    const std::string dir = Join(options.root, name);
    if (!Exists(Join(dir, "cgroup.procs")) || Exists(Join(dir, "cgroup.controllers"))) continue;
    for (const auto& [controller, file] : marker) {
      if (!mounts.count(controller) && Exists(Join(dir, file))) mounts[controller] = dir;
    }
  }
  std::vector<std::string> needed{"cpu"};
  if (options.use_cpuset) needed.push_back("cpuset");
  if (options.use_memory) needed.push_back("memory");
  std::map<std::string, std::string> bases;
  bool v1_ok = true;
  for (const std::string& c : needed) {
    if (!mounts.count(c)) {
      problems.push_back("cgroup v1: no hierarchy with the '" + c + "' controller under " +
                         options.root + " (looked for " + marker.at(c) + ")");
      v1_ok = false;
      continue;
    }
    if (!membership.count(c)) {
      problems.push_back("cgroup v1: no '" + c + "' line in " + options.self_cgroup_file);
      v1_ok = false;
      continue;
    }
    const std::string base = MountPlusPath(mounts.at(c), membership.at(c));
    if (std::string p = WritableProblem(base); !p.empty()) {
      problems.push_back("cgroup v1 '" + c + "': " + p);
      v1_ok = false;
      continue;
    }
    bases[c] = base;
  }
  if (v1_ok) {
    layout.version = CgroupVersion::kV1;
    layout.cpu_base = bases["cpu"];
    if (options.use_cpuset) layout.cpuset_base = bases["cpuset"];
    if (options.use_memory) layout.memory_base = bases["memory"];
    return layout;
  }
  for (const std::string& p : problems) {
    layout.problem += (layout.problem.empty() ? "" : "; ") + p;
  }
  return layout;
}

}  // namespace enavi::emulation
