#include "workers/emulation/cgroup_manager.h"

#include <sched.h>
#include <sys/stat.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <sstream>

#include "navstack/runtime/proc_stat.h"
#include "workers/emulation/cgroup_files.h"
#include "workers/emulation/cgroup_tree.h"
#include "workers/emulation/host_lock.h"

namespace enavi::emulation {

using cgroupfs::Join;
using cgroupfs::ReadTrimmed;
using cgroupfs::Subdirs;

namespace {

constexpr long kCgroupSuperMagic = 0x27e0eb;
constexpr long kCgroup2SuperMagic = 0x63677270;

bool OnCgroupFs(const std::string& path) {
  struct statfs fs{};
  if (statfs(path.c_str(), &fs) != 0) return false;
  return static_cast<long>(fs.f_type) == kCgroupSuperMagic ||
         static_cast<long>(fs.f_type) == kCgroup2SuperMagic;
}

}  // namespace

CgroupManager::OpenResult CgroupManager::Open(const CgroupOptions& options) {
  OpenResult result;
  if (options.parent_cpu_weight < 1 || options.parent_cpu_weight > 10000) {
    result.error = "cgroup options: parent_cpu_weight must be in [1, 10000], got " +
                   std::to_string(options.parent_cpu_weight);
    return result;
  }
  auto ctx = std::make_shared<CgroupContext>();
  ctx->options = options;
  ctx->layout = DetectCgroups(options);
  if (ctx->layout.version == CgroupVersion::kNone) {
    result.error = "cgroup CPU emulation unavailable: " + ctx->layout.problem;
    return result;
  }
  ctx->plain_files = !OnCgroupFs(ctx->layout.cpu_base);
  ctx->owner_pid = getpid();
  const auto start = navstack::ProcessStartTime(ctx->owner_pid);
  if (!start) {
    result.error = "cannot read the start time of this process from /proc/self/stat";
    return result;
  }
  ctx->owner_start = *start;
  {
    HostLock lock(options.lock_file);
    if (!lock.error().empty()) {
      result.error = lock.error();
      return result;
    }
    if (CgroupStatus s = EnsureParents(*ctx); !s.ok) {
      result.error = "cgroup CPU emulation unavailable: " + s.message;
      for (const std::string& p : ParentDirs(*ctx)) RemoveDir(*ctx, p);
      return result;
    }
  }
  result.manager.reset(new CgroupManager(std::move(ctx)));
  result.reaped = result.manager->ReapStale(&result.reap_errors);
  return result;
}

CgroupManager::CgroupManager(std::shared_ptr<const CgroupContext> context)
    : context_(std::move(context)) {}

CgroupManager::~CgroupManager() {
  context_->manager_alive = false;
  HostLock lock(context_->options.lock_file);
  RemoveParentsIfUnused(*context_);
}

const CgroupLayout& CgroupManager::layout() const { return context_->layout; }

std::vector<std::string> CgroupManager::ReapStale(std::string* errors) {
  HostLock lock(context_->options.lock_file);
  std::set<std::string> stale;
  for (const std::string& p : ParentDirs(*context_)) {
    for (const std::string& child : Subdirs(p)) {
      const auto name = ParseEpisodeName(child);
      if (name && !OwnerAlive(*name)) stale.insert(child);
    }
  }
  std::vector<std::string> removed;
  for (const std::string& name : stale) {
    const CgroupStatus s = RemoveEpisodeDirs(*context_, EpisodeDirs(*context_, name));
    if (s.ok) {
      removed.push_back(name);
    } else if (errors != nullptr) {
      *errors += (errors->empty() ? "" : "; ") + ("reaping " + name + ": " + s.message);
    }
  }
  return removed;
}

double CgroupManager::HostCpus() const {
  const CgroupLayout& l = context_->layout;
  if (!l.cpuset_base.empty()) {
    const bool v2 = l.version == CgroupVersion::kV2;
    for (const char* file : v2 ? std::vector<const char*>{"cpuset.cpus.effective", "cpuset.cpus"}
                               : std::vector<const char*>{"cpuset.effective_cpus", "cpuset.cpus"}) {
      const int n = CountCpuList(ReadTrimmed(Join(l.cpuset_base, file)));
      if (n > 0) return n;
    }
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return CPU_COUNT(&set);
  return static_cast<double>(sysconf(_SC_NPROCESSORS_ONLN));
}

double CgroupManager::ReservedCpus() const {
  const CgroupContext& ctx = *context_;
  const std::string parent = Join(ctx.layout.cpu_base, ctx.options.parent_name);
  double reserved = 0.0;
  for (const std::string& child : Subdirs(parent)) {
    const auto name = ParseEpisodeName(child);
    if (!name || !OwnerAlive(*name)) continue;
    const std::string dir = Join(parent, child);
    double quota = -1, period = 0;
    if (ctx.layout.version == CgroupVersion::kV2) {
      std::istringstream in(ReadTrimmed(Join(dir, "cpu.max")));
      std::string q;
      in >> q >> period;
      if (q != "max") quota = std::atof(q.c_str());
    } else {
      quota = std::atof(ReadTrimmed(Join(dir, "cpu.cfs_quota_us")).c_str());
      period = std::atof(ReadTrimmed(Join(dir, "cpu.cfs_period_us")).c_str());
    }
    if (quota > 0 && period > 0) reserved += quota / period;
  }
  return reserved;
}

CgroupManager::CreateResult CgroupManager::CreateEpisode(const BoardQuota& quota,
                                                         const EpisodeLimits& limits) {
  static std::atomic<int> counter{0};
  CreateResult result;
  const CgroupContext& ctx = *context_;
  HostLock lock(ctx.options.lock_file);
  if (!lock.error().empty()) {
    result.refusal = lock.error();
    return result;
  }
  if (CgroupStatus s = EnsureParents(ctx); !s.ok) {
    result.refusal = s.message;
    return result;
  }

  // Admission: the board's quota must fit in what the host has left.
  const double host = HostCpus();
  const double reserved = ReservedCpus();
  const double free_cpus = host - ctx.options.host_reserve_cpus - reserved;
  if (quota.BoardCpus() > free_cpus + 1e-9) {
    char buf[512];
    std::snprintf(buf, sizeof(buf),
                  "admission refused: the board needs %.3f host CPUs (%d cores x speed %.3f / "
                  "dilation %.2f) but only %.3f are free (host %.0f CPUs, %.3f held by running "
                  "emulations, %.2f kept for the simulator); raise the dilation or wait",
                  quota.BoardCpus(), quota.cores, quota.core_speed, quota.dilation,
                  std::max(0.0, free_cpus), host, reserved, ctx.options.host_reserve_cpus);
    result.refusal = buf;
    return result;
  }

  std::unique_ptr<EpisodeCgroup> group(new EpisodeCgroup());
  group->context_ = context_;
  group->quota_ = quota;
  group->name_ = "ep-" + std::to_string(ctx.owner_pid) + "-" + std::to_string(ctx.owner_start) +
                 "-" + std::to_string(counter.fetch_add(1));
  const auto dirs = EpisodeDirs(ctx, group->name_);
  group->cpu_dir_ = dirs[0].dir;
  for (const HierarchyDir& h : dirs) {
    if (mkdir(h.dir.c_str(), 0755) != 0) {
      result.refusal = "cannot create " + h.dir + ": " + std::strerror(errno);
      group->removed_ = true;
      RemoveEpisodeDirs(ctx, dirs);
      return result;
    }
  }
  const CgroupLayout& l = ctx.layout;
  std::vector<std::pair<std::string, std::string>> writes;  // file, value, in order
  const std::string period = std::to_string(quota.period_us);
  const std::string board_quota = std::to_string(quota.board_quota_us);
  if (l.version == CgroupVersion::kV2) {
    const std::string& d = group->cpu_dir_;
    writes.emplace_back(Join(d, "cpu.max"), board_quota + " " + period);
    if (!l.cpuset_base.empty()) {
      group->cpuset_dir_ = d;
      if (!limits.cpus.empty()) writes.emplace_back(Join(d, "cpuset.cpus"), limits.cpus);
    }
    if (!l.memory_base.empty()) {
      group->memory_dir_ = d;
      if (limits.memory_bytes > 0) {
        writes.emplace_back(Join(d, "memory.max"), std::to_string(limits.memory_bytes));
      }
    }
  } else {
    const std::string& d = group->cpu_dir_;
    writes.emplace_back(Join(d, "cpu.cfs_period_us"), period);
    writes.emplace_back(Join(d, "cpu.cfs_quota_us"), board_quota);
    std::size_t next = 1;
    if (!l.cpuset_base.empty()) {
      group->cpuset_dir_ = dirs[next++].dir;
      const std::string parent = Join(l.cpuset_base, ctx.options.parent_name);
      const std::string cpus = limits.cpus.empty() ? ReadTrimmed(Join(parent, "cpuset.cpus")) : limits.cpus;
      writes.emplace_back(Join(group->cpuset_dir_, "cpuset.cpus"), cpus);
      writes.emplace_back(Join(group->cpuset_dir_, "cpuset.mems"), ReadTrimmed(Join(parent, "cpuset.mems")));
    }
    if (!l.memory_base.empty()) {
      group->memory_dir_ = dirs[next++].dir;
      if (limits.memory_bytes > 0) {
        writes.emplace_back(Join(group->memory_dir_, "memory.limit_in_bytes"),
                            std::to_string(limits.memory_bytes));
      }
    }
  }
  for (const auto& [file, value] : writes) {
    if (CgroupStatus s = WriteValue(ctx, file, value); !s.ok) {
      result.refusal = "configuring episode cgroup: " + s.message;
      group->removed_ = true;
      RemoveEpisodeDirs(ctx, dirs);
      return result;
    }
  }
  result.group = std::move(group);
  return result;
}

}  // namespace enavi::emulation
