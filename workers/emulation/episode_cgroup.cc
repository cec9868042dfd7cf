#include "workers/emulation/episode_cgroup.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <utility>
#include <vector>

#include "workers/emulation/cgroup_files.h"
#include "workers/emulation/cgroup_tree.h"
#include "workers/emulation/host_lock.h"

namespace enavi::emulation {

using cgroupfs::Join;
using cgroupfs::ReadPids;
using cgroupfs::ReadTrimmed;
using cgroupfs::Subdirs;
using cgroupfs::Words;

EpisodeCgroup::~EpisodeCgroup() { Remove(); }

CgroupStatus EpisodeCgroup::AddProcess(pid_t pid) {
  const CgroupContext& ctx = *context_;
  std::vector<std::string> dirs{cpu_dir_};
  if (ctx.layout.version == CgroupVersion::kV1) {
    if (!cpuset_dir_.empty()) dirs.push_back(cpuset_dir_);
    if (!memory_dir_.empty()) dirs.push_back(memory_dir_);
  }
  for (const std::string& d : dirs) {
    if (CgroupStatus s = WriteValue(ctx, Join(d, "cgroup.procs"), std::to_string(pid)); !s.ok) {
      return s;
    }
  }
  return {};
}

CgroupStatus EpisodeCgroup::AddThread(pid_t tid) {
  const CgroupContext& ctx = *context_;
  const std::string dir = Join(cpu_dir_, "t-" + std::to_string(tid));
  if (mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) {
    return {false, "cannot create " + dir + ": " + std::strerror(errno)};
  }
  const std::string period = std::to_string(quota_.period_us);
  const std::string core_quota = std::to_string(quota_.core_quota_us);
  std::vector<std::pair<std::string, std::string>> writes;
  if (ctx.layout.version == CgroupVersion::kV2) {
    // A threaded child turns the episode group into a threaded domain; cpu is a threaded
    // controller, so it can then be enabled for the children.
    if (ReadTrimmed(Join(dir, "cgroup.type")) != "threaded") {
      writes.emplace_back(Join(dir, "cgroup.type"), "threaded");
    }
    if (!Words(ReadTrimmed(Join(cpu_dir_, "cgroup.subtree_control"))).count("cpu")) {
      writes.emplace_back(Join(cpu_dir_, "cgroup.subtree_control"), "+cpu");
    }
    writes.emplace_back(Join(dir, "cpu.max"), core_quota + " " + period);
    writes.emplace_back(Join(dir, "cgroup.threads"), std::to_string(tid));
  } else {
    writes.emplace_back(Join(dir, "cpu.cfs_period_us"), period);
    writes.emplace_back(Join(dir, "cpu.cfs_quota_us"), core_quota);
    writes.emplace_back(Join(dir, "tasks"), std::to_string(tid));
  }
  for (const auto& [file, value] : writes) {
    if (CgroupStatus s = WriteValue(ctx, file, value); !s.ok) return s;
  }
  return {};
}

int EpisodeCgroup::SweepThreads(CgroupStatus* status) {
  const CgroupContext& ctx = *context_;
  int placed = 0;
  CgroupStatus total;
  auto place = [&](pid_t tid) {
    if (CgroupStatus s = AddThread(tid); s.ok) {
      ++placed;
    } else if (total.ok) {
      total = s;
    }
  };
  for (pid_t tid : ReadPids(Join(cpu_dir_, TaskFile(ctx)))) place(tid);
  // A thread started by a thread that already has its group lands in that group, sharing its
  // one board core; it gets its own. Groups of threads that exited are removed.
  if (!ctx.plain_files) {
    for (const std::string& child : Subdirs(cpu_dir_)) {
      if (!IsThreadDirName(child)) continue;
      const std::string dir = Join(cpu_dir_, child);
      const std::vector<pid_t> tids = ReadPids(Join(dir, TaskFile(ctx)));
      if (tids.empty()) {
        rmdir(dir.c_str());
        continue;
      }
      const std::string owner = child.substr(2);  // t-<tid>
      for (pid_t tid : tids)
        if (std::to_string(tid) != owner) place(tid);
    }
  }
  if (status != nullptr) *status = total;
  return placed;
}

std::vector<pid_t> EpisodeCgroup::Tasks() const { return TasksBelow(*context_, cpu_dir_); }

CpuStat EpisodeCgroup::ReadCpuStat() const {
  CpuStat stat;
  std::ifstream in(Join(cpu_dir_, "cpu.stat"));
  std::string key;
  std::int64_t value = 0;
  while (in >> key >> value) {
    if (key == "nr_periods") stat.nr_periods = value;
    if (key == "nr_throttled") stat.nr_throttled = value;
    if (key == "throttled_time") stat.throttled_ns = value;          // v1, ns
    if (key == "throttled_usec") stat.throttled_ns = value * 1000;   // v2, us
  }
  return stat;
}

bool EpisodeCgroup::KillTasks(double timeout_s) {
  if (removed_ || !context_) return true;
  return EmptyEpisodeDirs(*context_, EpisodeDirs(*context_, name_), std::max(1, static_cast<int>(timeout_s * 100)));
}

CgroupStatus EpisodeCgroup::Remove(bool with_parent) {
  if (removed_ || !context_) return {};
  removed_ = true;
  HostLock lock(context_->options.lock_file);
  CgroupStatus status = RemoveEpisodeDirs(*context_, EpisodeDirs(*context_, name_));
  if (with_parent || !context_->manager_alive) RemoveParentsIfUnused(*context_);
  return status;
}

}  // namespace enavi::emulation
