#include "workers/board/cgroup.h"

#include <dirent.h>
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

namespace enavi::board {

// Everything a manager and its episode groups share: options, detection result, whether the
// tree is a real cgroup filesystem (a fake tree in tests gets plain files and no kills).
struct CgroupContext {
  CgroupOptions options;
  CgroupLayout layout;
  bool fake = false;
  pid_t owner_pid = 0;
  std::uint64_t owner_start = 0;
  // An episode that outlives its manager removes the parent itself when it is the last one.
  mutable std::atomic<bool> manager_alive{true};
};

namespace {

constexpr long kCgroupSuperMagic = 0x27e0eb;
constexpr long kCgroup2SuperMagic = 0x63677270;

std::string Join(const std::string& dir, const std::string& name) {
  if (dir.empty()) return name;
  if (dir.back() == '/') return dir + name;
  return dir + "/" + name;
}

// Joins a mount point and a cgroup path from /proc/self/cgroup ("/" is the mount itself).
std::string MountPlusPath(const std::string& mount, const std::string& path) {
  if (path.empty() || path == "/") return mount;
  return mount + (path.front() == '/' ? path : "/" + path);
}

bool Exists(const std::string& path) {
  struct stat st{};
  return stat(path.c_str(), &st) == 0;
}

bool IsDir(const std::string& path) {
  struct stat st{};
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool ReadFile(const std::string& path, std::string* out) {
  std::ifstream in(path);
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return true;
}

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

std::string ReadTrimmed(const std::string& path) {
  std::string s;
  if (!ReadFile(path, &s)) return {};
  return Trim(s);
}

// One write() of the whole value: cgroup files take one value per write.
CgroupStatus WriteValue(const CgroupContext& ctx, const std::string& path, const std::string& value) {
  const int flags = O_WRONLY | O_CLOEXEC | (ctx.fake ? (O_CREAT | O_TRUNC) : 0);
  const int fd = open(path.c_str(), flags, 0644);
  if (fd < 0) {
    return {false, "cannot open " + path + " for writing: " + std::strerror(errno)};
  }
  const ssize_t n = write(fd, value.data(), value.size());
  const int err = errno;
  close(fd);
  if (n != static_cast<ssize_t>(value.size())) {
    return {false, "writing '" + value + "' to " + path + ": " + std::strerror(err)};
  }
  return {};
}

std::vector<std::string> Subdirs(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = opendir(dir.c_str());
  if (d == nullptr) return names;
  while (dirent* e = readdir(d)) {
    const std::string name = e->d_name;
    if (name == "." || name == "..") continue;
    if (IsDir(Join(dir, name))) names.push_back(name);
  }
  closedir(d);
  return names;
}

std::vector<pid_t> ReadPids(const std::string& path) {
  std::vector<pid_t> pids;
  std::ifstream in(path);
  long v = 0;
  while (in >> v) pids.push_back(static_cast<pid_t>(v));
  return pids;
}

// Start time (clock ticks since boot, /proc/<pid>/stat field 22) and liveness of a process.
// A zombie counts as gone: it will never run again.
std::optional<std::uint64_t> LiveStartTime(pid_t pid) {
  std::string line;
  if (!ReadFile("/proc/" + std::to_string(pid) + "/stat", &line)) return std::nullopt;
  const auto close = line.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream rest(line.substr(close + 1));
  std::string field;
  std::uint64_t start = 0;
  for (int index = 3; index <= 22 && rest >> field; ++index) {
    if (index == 3 && (field == "Z" || field == "X")) return std::nullopt;
    if (index == 22) start = std::stoull(field);
  }
  if (!rest) return std::nullopt;
  return start;
}

pid_t TgidOf(pid_t tid) {
  std::ifstream in("/proc/" + std::to_string(tid) + "/status");
  std::string key;
  while (in >> key) {
    if (key == "Tgid:") {
      long v = 0;
      in >> v;
      return static_cast<pid_t>(v);
    }
    std::string rest;
    std::getline(in, rest);
  }
  return 0;
}

// Episode group names: ep-<pid>-<start>-<n>.
struct EpisodeName {
  pid_t pid = 0;
  std::uint64_t start = 0;
};

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
  const auto start = LiveStartTime(e.pid);
  return start.has_value() && *start == e.start;
}

bool IsThreadDirName(const std::string& name) {
  return name.size() > 2 && name.compare(0, 2, "t-") == 0 &&
         name.find_first_not_of("0123456789", 2) == std::string::npos;
}

bool OnCgroupFs(const std::string& path) {
  struct statfs fs{};
  if (statfs(path.c_str(), &fs) != 0) return false;
  return static_cast<long>(fs.f_type) == kCgroupSuperMagic ||
         static_cast<long>(fs.f_type) == kCgroup2SuperMagic;
}

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

std::set<std::string> Words(const std::string& s) {
  std::set<std::string> words;
  std::istringstream in(s);
  std::string w;
  while (in >> w) words.insert(w);
  return words;
}

// Serialises admission and parent creation/removal among the workers of a host.
class HostLock {
 public:
  explicit HostLock(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) {
      error_ = "cannot open lock file " + path + ": " + std::strerror(errno);
      return;
    }
    while (flock(fd_, LOCK_EX) != 0) {
      if (errno != EINTR) {
        error_ = "cannot lock " + path + ": " + std::strerror(errno);
        return;
      }
    }
  }
  ~HostLock() {
    if (fd_ >= 0) close(fd_);  // releases the lock
  }
  const std::string& error() const { return error_; }

 private:
  int fd_ = -1;
  std::string error_;
};

// The directories one episode (or the parent) spans, with the home group of each hierarchy
// where threads of this process go back to.
struct HierarchyDir {
  std::string dir;
  std::string home;
  bool is_cpu = false;
};

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

// Thread ids in `dir` and its t-* children.
std::vector<pid_t> TasksBelow(const CgroupContext& ctx, const std::string& dir) {
  std::vector<pid_t> tids = ReadPids(Join(dir, TaskFile(ctx)));
  for (const std::string& child : Subdirs(dir)) {
    if (!IsThreadDirName(child)) continue;
    for (pid_t t : ReadPids(Join(Join(dir, child), TaskFile(ctx)))) tids.push_back(t);
  }
  return tids;
}

// Removes a directory we created. On a real cgroup fs rmdir works on a group without tasks
// or children; a fake tree holds plain files that go first.
CgroupStatus RemoveDir(const CgroupContext& ctx, const std::string& dir) {
  if (!IsDir(dir)) return {};
  if (ctx.fake) {
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

// Empties and removes an episode's directories: threads of this process go home, other
// processes are killed (they are the episode's navstack, or orphans of a crashed worker).
CgroupStatus RemoveEpisodeDirs(const CgroupContext& ctx, const std::vector<HierarchyDir>& dirs) {
  CgroupStatus status;
  auto fail = [&status](const std::string& message) {
    status.ok = false;
    status.message += (status.message.empty() ? "" : "; ") + message;
  };
  if (!ctx.fake) {
    const pid_t self = getpid();
    std::set<pid_t> killed;
    bool empty = false;
    for (int attempt = 0; attempt < 500 && !empty; ++attempt) {  // <= ~5 s
      empty = true;
      for (const HierarchyDir& h : dirs) {
        for (pid_t tid : TasksBelow(ctx, h.dir)) {
          empty = false;
          const pid_t tgid = TgidOf(tid);
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
      if (!empty) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!empty) fail("tasks still inside after SIGKILL and 5 s of waiting");
  }
  for (const HierarchyDir& h : dirs) {
    for (const std::string& child : Subdirs(h.dir)) {
      if (!IsThreadDirName(child)) continue;
      if (CgroupStatus s = RemoveDir(ctx, Join(h.dir, child)); !s.ok) fail(s.message);
    }
    if (CgroupStatus s = RemoveDir(ctx, h.dir); !s.ok) fail(s.message);
  }
  return status;
}

// Creates (if needed) and configures the `enavi` parent in every hierarchy.
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

// Removes the parents unless some worker still has episodes in them (it must stay for them).
void RemoveParentsIfUnused(const CgroupContext& ctx) {
  for (const std::string& p : ParentDirs(ctx)) {
    bool has_episodes = false;
    for (const std::string& child : Subdirs(p)) has_episodes |= ParseEpisodeName(child).has_value();
    if (!has_episodes) RemoveDir(ctx, p);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Detection

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

// ---------------------------------------------------------------------------------------------
// CgroupManager

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
  ctx->fake = !OnCgroupFs(ctx->layout.cpu_base);
  ctx->owner_pid = getpid();
  const auto start = LiveStartTime(ctx->owner_pid);
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

// ---------------------------------------------------------------------------------------------
// EpisodeCgroup

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
  for (pid_t tid : ReadPids(Join(cpu_dir_, TaskFile(ctx)))) {
    if (CgroupStatus s = AddThread(tid); s.ok) {
      ++placed;
    } else if (total.ok) {
      total = s;
    }
  }
  // Groups of threads that exited.
  if (!ctx.fake) {
    for (const std::string& child : Subdirs(cpu_dir_)) {
      const std::string dir = Join(cpu_dir_, child);
      if (IsThreadDirName(child) && ReadPids(Join(dir, TaskFile(ctx))).empty()) rmdir(dir.c_str());
    }
  }
  if (status != nullptr) *status = total;
  return placed;
}

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

CgroupStatus EpisodeCgroup::Remove() {
  if (removed_ || !context_) return {};
  removed_ = true;
  HostLock lock(context_->options.lock_file);
  CgroupStatus status = RemoveEpisodeDirs(*context_, EpisodeDirs(*context_, name_));
  if (!context_->manager_alive) RemoveParentsIfUnused(*context_);
  return status;
}

}  // namespace enavi::board
