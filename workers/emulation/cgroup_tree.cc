#include "workers/emulation/cgroup_tree.h"

#include <dirent.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <set>
#include <thread>

#include "navstack/runtime/proc_stat.h"
#include "workers/emulation/cgroup_files.h"

namespace enavi::emulation {

using cgroupfs::IsDir;
using cgroupfs::Join;
using cgroupfs::ReadPids;
using cgroupfs::ReadTrimmed;
using cgroupfs::Subdirs;

std::vector<pid_t> TasksBelow(const CgroupContext& ctx, const std::string& dir) {
  std::vector<pid_t> tids = ReadPids(Join(dir, TaskFile(ctx)));
  for (const std::string& child : Subdirs(dir)) {
    if (!IsThreadDirName(child)) continue;
    for (pid_t t : ReadPids(Join(Join(dir, child), TaskFile(ctx)))) tids.push_back(t);
  }
  return tids;
}

std::optional<EpisodeName> ParseEpisodeName(const std::string& name) {
  unsigned long pid = 0, n = 0;
  unsigned long long start = 0;
  int consumed = 0;
  if (std::sscanf(name.c_str(), "ep-%lu-%llu-%lu%n", &pid, &start, &n, &consumed) != 3 ||
      consumed != static_cast<int>(name.size())) {
    return std::nullopt;
  }
  return EpisodeName{static_cast<pid_t>(pid), start};
}

bool OwnerAlive(const EpisodeName& e) {
  const auto start = navstack::ProcessStartTime(e.pid);
  return start.has_value() && *start == e.start;
}

bool IsThreadDirName(const std::string& name) {
  return name.size() > 2 && name.compare(0, 2, "t-") == 0 &&
         name.find_first_not_of("0123456789", 2) == std::string::npos;
}

std::vector<HierarchyDir> EpisodeDirs(const CgroupContext& ctx, const std::string& name) {
  const CgroupLayout& l = ctx.layout;
  const std::string& parent = ctx.options.parent_name;
  std::vector<HierarchyDir> dirs;
  dirs.push_back({Join(Join(l.cpu_base, parent), name), l.cpu_base, true});
  if (l.version == CgroupVersion::kV1) {
    if (!l.cpuset_base.empty()) dirs.push_back({Join(Join(l.cpuset_base, parent), name), l.cpuset_base, false});
    if (!l.memory_base.empty()) dirs.push_back({Join(Join(l.memory_base, parent), name), l.memory_base, false});
  }
  return dirs;
}

std::vector<std::string> ParentDirs(const CgroupContext& ctx) {
  const CgroupLayout& l = ctx.layout;
  std::vector<std::string> dirs{Join(l.cpu_base, ctx.options.parent_name)};
  if (l.version == CgroupVersion::kV1) {
    if (!l.cpuset_base.empty()) dirs.push_back(Join(l.cpuset_base, ctx.options.parent_name));
    if (!l.memory_base.empty()) dirs.push_back(Join(l.memory_base, ctx.options.parent_name));
  }
  return dirs;
}

const char* TaskFile(const CgroupContext& ctx) {
  return ctx.layout.version == CgroupVersion::kV2 ? "cgroup.threads" : "tasks";
}

CgroupStatus WriteValue(const CgroupContext& ctx, const std::string& path, const std::string& value) {
  return cgroupfs::WriteValue(path, value, ctx.plain_files);
}

CgroupStatus RemoveDir(const CgroupContext& ctx, const std::string& dir) {
  if (!IsDir(dir)) return {};
  if (ctx.plain_files) {
    DIR* d = opendir(dir.c_str());
    if (d != nullptr) {
      while (dirent* e = readdir(d)) {
        const std::string path = Join(dir, e->d_name);
        struct stat st{};
        if (lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) unlink(path.c_str());
      }
      closedir(d);
    }
  }
  if (rmdir(dir.c_str()) != 0 && errno != ENOENT) {
    return {false, "rmdir " + dir + ": " + std::strerror(errno)};
  }
  return {};
}

bool EmptyEpisodeDirs(const CgroupContext& ctx, const std::vector<HierarchyDir>& dirs, int attempts) {
  if (ctx.plain_files) return true;
  const pid_t self = getpid();
  std::set<pid_t> killed;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    bool empty = true;
    for (const HierarchyDir& h : dirs) {
      for (pid_t tid : TasksBelow(ctx, h.dir)) {
        empty = false;
        const pid_t tgid = navstack::ThreadGroupOf(tid);
        if (tgid == self) {
          // v1 moves single threads; in v2 only the whole process can leave a threaded subtree.
          if (ctx.layout.version == CgroupVersion::kV2) {
            WriteValue(ctx, Join(h.home, "cgroup.procs"), std::to_string(self));
          } else {
            WriteValue(ctx, Join(h.home, "tasks"), std::to_string(tid));
          }
        } else if (tgid > 0 && killed.insert(tgid).second) {
          kill(tgid, SIGKILL);
        }
      }
    }
    if (empty) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

CgroupStatus RemoveEpisodeDirs(const CgroupContext& ctx, const std::vector<HierarchyDir>& dirs) {
  CgroupStatus status;
  auto fail = [&status](const std::string& message) {
    status.ok = false;
    status.message += (status.message.empty() ? "" : "; ") + message;
  };
  if (!EmptyEpisodeDirs(ctx, dirs, 500)) fail("tasks still inside after SIGKILL and 5 s of waiting");  // <= ~5 s
  for (const HierarchyDir& h : dirs) {
    for (const std::string& child : Subdirs(h.dir)) {
      if (!IsThreadDirName(child)) continue;
      if (CgroupStatus s = RemoveDir(ctx, Join(h.dir, child)); !s.ok) fail(s.message);
    }
    if (CgroupStatus s = RemoveDir(ctx, h.dir); !s.ok) fail(s.message);
  }
  return status;
}

CgroupStatus EnsureParents(const CgroupContext& ctx) {
  const CgroupLayout& l = ctx.layout;
  const std::vector<std::string> parents = ParentDirs(ctx);
  for (const std::string& p : parents) {
    if (mkdir(p.c_str(), 0755) != 0 && errno != EEXIST) {
      return {false, "cannot create " + p + ": " + std::strerror(errno)};
    }
  }
  const int weight = ctx.options.parent_cpu_weight;
  if (l.version == CgroupVersion::kV2) {
    std::string controllers = "+cpu";
    if (ctx.options.use_cpuset) controllers += " +cpuset";
    if (ctx.options.use_memory) controllers += " +memory";
    if (auto s = WriteValue(ctx, Join(parents[0], "cgroup.subtree_control"), controllers); !s.ok) return s;
    return WriteValue(ctx, Join(parents[0], "cpu.weight"), std::to_string(weight));
  }
  if (auto s = WriteValue(ctx, Join(parents[0], "cpu.shares"), std::to_string(weight * 1024 / 100)); !s.ok) {
    return s;
  }
  if (!l.cpuset_base.empty()) {
    // A new v1 cpuset is empty and takes no tasks: copy the worker's own cpus and mems.
    const std::string parent = Join(l.cpuset_base, ctx.options.parent_name);
    for (const char* file : {"cpuset.cpus", "cpuset.mems"}) {
      const std::string value = ReadTrimmed(Join(l.cpuset_base, file));
      if (value.empty()) {
        return {false, "cannot read " + Join(l.cpuset_base, file) + " (empty)"};
      }
      if (ReadTrimmed(Join(parent, file)) == value) continue;
      if (auto s = WriteValue(ctx, Join(parent, file), value); !s.ok) return s;
    }
  }
  return {};
}

void RemoveParentsIfUnused(const CgroupContext& ctx) {
  for (const std::string& p : ParentDirs(ctx)) {
    bool has_episodes = false;
    for (const std::string& child : Subdirs(p)) has_episodes |= ParseEpisodeName(child).has_value();
    if (!has_episodes) RemoveDir(ctx, p);
  }
}

}  // namespace enavi::emulation
