// How SCHED_DEADLINE meets CFS bandwidth control and cpusets, measured on this kernel.
// Run as root: dl_cgroup_experiment [--json]. Every group it makes is an enavi episode group,
// removed at exit. Findings and their use in the emulation: workers/board/EMULATION.md.
#include <sched.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "navstack/runtime/sched_deadline.h"
#include "workers/emulation/cgroup_manager.h"

namespace {

using enavi::emulation::BoardCpu;
using enavi::emulation::CgroupManager;
using enavi::emulation::ComputeBoardQuota;
using enavi::emulation::EpisodeCgroup;
using enavi::emulation::EpisodeLimits;
using enavi::navstack::DeadlineParams;

double Now(clockid_t c) {
  timespec ts{};
  clock_gettime(c, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

constexpr int kMax = 16;
struct Block {
  std::atomic<int> ready{0};
  std::atomic<int> go{0};
  std::atomic<int> asked{0};
  pid_t tid[kMax] = {};
  int policy_errno[kMax] = {};  // after the policy request: 0 = granted
  double share[kMax] = {};      // CPU / wall while spinning
};

// Policy a thread asks for once it is in its group.
struct ThreadPlan {
  enum Kind { kOther, kDeadline, kFifo } kind = kOther;
  DeadlineParams dl;
};

// Forks a child with one thread per plan; the parent places the process (and each thread in its
// own per-core group) in `group`; then each thread asks for its policy and spins `seconds`.
std::vector<std::pair<int, double>> Run(const std::vector<ThreadPlan>& plans, EpisodeCgroup* group,
                                        double seconds) {
  auto* b = new (mmap(nullptr, sizeof(Block), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS,
                      -1, 0)) Block();
  const int n = static_cast<int>(plans.size());
  const pid_t child = fork();
  if (child == 0) {
    std::vector<std::thread> threads;
    for (int i = 0; i < n; ++i) {
      threads.emplace_back([b, i, &plans, seconds] {
        b->tid[i] = static_cast<pid_t>(gettid());
        b->ready.fetch_add(1);
        while (b->go.load() == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
        if (plans[i].kind == ThreadPlan::kDeadline) {
          enavi::navstack::DeadlineOptions o;
          o.ebusy_retries = 0;
          const auto r = enavi::navstack::EnterDeadline(plans[i].dl, o);
          b->policy_errno[i] = r.deadline ? 0 : r.error;
        } else if (plans[i].kind == ThreadPlan::kFifo) {
          sched_param p{};
          p.sched_priority = 10;
          b->policy_errno[i] = sched_setscheduler(0, SCHED_FIFO, &p) == 0 ? 0 : errno;
        }
        // Hold the reservation (sleeping) until every thread has asked: a spinning DL thread
        // would starve the CFS threads that have not asked yet.
        b->asked.fetch_add(1);
        while (b->asked.load() < static_cast<int>(plans.size())) {
          std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
        const double w0 = Now(CLOCK_MONOTONIC), c0 = Now(CLOCK_THREAD_CPUTIME_ID);
        volatile unsigned long x = 0;
        // A FIFO thread that was granted must not spin unbounded: cap it like the others.
        while (Now(CLOCK_MONOTONIC) - w0 < seconds) x = x + 1;
        b->share[i] = (Now(CLOCK_THREAD_CPUTIME_ID) - c0) / (Now(CLOCK_MONOTONIC) - w0);
      });
    }
    for (auto& t : threads) t.join();
    _exit(0);
  }
  while (b->ready.load() < n) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  if (group != nullptr) {
    group->AddProcess(child);
    for (int i = 0; i < n; ++i) group->AddThread(b->tid[i]);
  }
  b->go.store(1);
  waitpid(child, nullptr, 0);
  std::vector<std::pair<int, double>> out;
  for (int i = 0; i < n; ++i) out.emplace_back(b->policy_errno[i], b->share[i]);
  munmap(b, sizeof(Block));
  return out;
}

ThreadPlan Dl(double rate, std::int64_t period_ns = 10'000'000) {
  ThreadPlan p;
  p.kind = ThreadPlan::kDeadline;
  p.dl = enavi::navstack::SpeedServerParams(rate, period_ns);
  return p;
}

long ReadLong(const char* path) {
  long v = -1;
  if (FILE* f = std::fopen(path, "r")) {
    if (std::fscanf(f, "%ld", &v) != 1) v = -1;
    std::fclose(f);
  }
  return v;
}

std::string Err(int e) { return e == 0 ? "granted" : std::string(strerrorname_np(e)); }

}  // namespace

int main(int argc, char** argv) {
  bool json = false;
  enavi::emulation::CgroupOptions options;
  std::string only;  // --only E5: run one experiment
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--json") json = true;
    if (a == "--only" && i + 1 < argc) only = argv[++i];
    if (a == "--no-cpuset") options.use_cpuset = false;
  }
  auto want = [&only](const char* id) {
    return only.empty() || ("," + only + ",").find("," + std::string(id) + ",") != std::string::npos;
  };
  if (geteuid() != 0) {
    std::fprintf(stderr, "dl_cgroup_experiment: needs root (cgroups, SCHED_DEADLINE)\n");
    return 2;
  }
  auto open = CgroupManager::Open(options);
  if (!open.ok()) {
    std::fprintf(stderr, "%s\n", open.error.c_str());
    return 1;
  }
  nlohmann::json report = nlohmann::json::array();
  auto add = [&](const std::string& id, const std::string& setup, const std::string& observed,
                 const std::string& finding) {
    report.push_back({{"id", id}, {"setup", setup}, {"observed", observed}, {"finding", finding}});
    if (!json) {
      std::printf("%s\n  setup:    %s\n  observed: %s\n  finding:  %s\n\n", id.c_str(), setup.c_str(),
                  observed.c_str(), finding.c_str());
    }
  };
  char buf[512];

  // E1: a DL thread inside a group whose CFS quota is 0.2 CPU.
  if (want("E1")) {
    auto g = open.manager->CreateEpisode(ComputeBoardQuota(BoardCpu{1, 0.2}, {}));
    const auto r = Run({ThreadPlan{}, Dl(0.6)}, g.group.get(), 1.5);
    std::snprintf(buf, sizeof(buf), "SCHED_OTHER thread share %.3f; SCHED_DEADLINE (0.6) thread %s, share %.3f",
                  r[0].second, Err(r[1].first).c_str(), r[1].second);
    add("E1 cfs_quota_vs_deadline",
        "board group and per-thread groups with cpu.cfs_quota_us = 0.2 CPU (20 ms period); "
        "one spinning SCHED_OTHER thread, one spinning thread with SCHED_DEADLINE 6 ms / 10 ms",
        buf, "CFS bandwidth control does not bind SCHED_DEADLINE threads: the DL thread gets its "
             "DL runtime, not the group's quota");
  }
  // E2: DL runtime is not charged to the group's CFS quota.
  if (want("E2")) {
    auto g = open.manager->CreateEpisode(ComputeBoardQuota(BoardCpu{1, 0.5}, {}));
    const auto r = Run({Dl(0.4), ThreadPlan{}}, g.group.get(), 1.5);
    std::snprintf(buf, sizeof(buf), "DL (0.4) thread %s share %.3f; CFS thread share %.3f (quota 0.5)",
                  Err(r[0].first).c_str(), r[0].second, r[1].second);
    add("E2 dl_not_charged_to_quota",
        "group quota 0.5 CPU; a SCHED_DEADLINE 4 ms / 10 ms thread and a SCHED_OTHER thread",
        buf, "the DL thread's CPU is not taken from the group's CFS quota: the board group "
             "would grant the board's capacity on top of every DL reservation in it");
  }
  // E3: DL is accepted in a non-root cpu cgroup whose cpu.rt_runtime_us is 0; FIFO is not.
  if (want("E3")) {
    auto g = open.manager->CreateEpisode(ComputeBoardQuota(BoardCpu{1, 0.5}, {}));
    ThreadPlan fifo;
    fifo.kind = ThreadPlan::kFifo;
    const auto r = Run({Dl(0.2), fifo}, g.group.get(), 0.2);
    std::snprintf(buf, sizeof(buf), "SCHED_DEADLINE: %s; SCHED_FIFO: %s", Err(r[0].first).c_str(),
                  Err(r[1].first).c_str());
    add("E3 dl_in_non_root_cgroup",
        "thread in an enavi per-thread cpu group (cpu.rt_runtime_us = 0, RT_GROUP_SCHED kernel)",
        buf, "the kernel does not refuse SCHED_DEADLINE inside a non-root cpu cgroup; the "
             "RT-group runtime check applies to SCHED_FIFO/RR only");
  }
  // E4: DL in a cpuset narrower than the root domain.
  if (want("E4") && options.use_cpuset) {
    EpisodeLimits limits;
    limits.cpus = "0";
    auto g = open.manager->CreateEpisode(ComputeBoardQuota(BoardCpu{1, 0.5}, {}), limits);
    const auto r = Run({Dl(0.2)}, g.group.get(), 0.2);
    auto g2 = open.manager->CreateEpisode(ComputeBoardQuota(BoardCpu{1, 0.5}, {}));
    const auto r2 = Run({Dl(0.2)}, g2.group.get(), 0.2);
    std::snprintf(buf, sizeof(buf), "cpuset.cpus = 0: %s; cpuset.cpus = all: %s",
                  Err(r[0].first).c_str(), Err(r2[0].first).c_str());
    add("E4 dl_in_narrow_cpuset",
        "episode cpuset with cpus = \"0\" on a 2-CPU root domain, then with all CPUs", buf,
        "sched_setattr(SCHED_DEADLINE) needs the thread's affinity to span its whole root domain: "
        "a board cpuset narrower than the host refuses DL with EPERM (unless made an exclusive "
        "partition with its own root domain, which the emulation does not do)");
  }
  // E5: total DL bandwidth admitted on the root domain.
  if (want("E5")) {
    std::vector<ThreadPlan> plans(kMax, Dl(0.15, 100'000'000));
    const auto r = Run(plans, nullptr, 0.3);
    int granted = 0;
    for (const auto& [e, share] : r) granted += e == 0;
    std::snprintf(buf, sizeof(buf),
                  "%d of %d reservations of 0.15 granted = %.2f CPUs (sched_rt_runtime_us %ld, "
                  "sched_rt_period_us %ld, %ld CPUs)",
                  granted, kMax, granted * 0.15, ReadLong("/proc/sys/kernel/sched_rt_runtime_us"),
                  ReadLong("/proc/sys/kernel/sched_rt_period_us"), sysconf(_SC_NPROCESSORS_ONLN));
    add("E5 dl_admission_limit",
        "16 threads each asking SCHED_DEADLINE 15 ms / 100 ms, no retries", buf,
        "admission is per root domain: sum(runtime/period) <= sched_rt_runtime_us / "
        "sched_rt_period_us x CPUs minus the fair server's reservation (6.12+: 50 ms / 1 s per "
        "CPU); here 2 x (0.95 - 0.05) = 1.8 CPUs. Refusals are EBUSY");
  }
  // E6: a hard DL reservation as a speed server.
  if (want("E6")) {
    const auto r = Run({Dl(0.3)}, nullptr, 1.5);
    std::snprintf(buf, sizeof(buf), "share %.3f (asked 0.300)", r[0].second);
    add("E6 dl_speed_server",
        "one spinning thread with SCHED_DEADLINE 3 ms / 10 ms, no SCHED_FLAG_RECLAIM, idle CPUs", buf,
        "a non-reclaiming DL reservation throttles the thread at runtime/period even when the "
        "CPU is idle: it emulates one board core of speed s / k, and (unlike a CFS quota, a "
        "ceiling only) also guarantees that rate against other load");
  }
  // E7: bandwidth of exited DL threads comes back only at their 0-lag time.
  if (want("E7")) {
    const auto first = Run({Dl(0.85, 100'000'000), Dl(0.85, 100'000'000)}, nullptr, 0.05);
    const auto again = Run({Dl(0.85, 100'000'000), Dl(0.85, 100'000'000)}, nullptr, 0.05);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const auto later = Run({Dl(0.85, 100'000'000), Dl(0.85, 100'000'000)}, nullptr, 0.05);
    std::snprintf(buf, sizeof(buf), "first: %s/%s; right after: %s/%s; 300 ms later: %s/%s",
                  Err(first[0].first).c_str(), Err(first[1].first).c_str(),
                  Err(again[0].first).c_str(), Err(again[1].first).c_str(),
                  Err(later[0].first).c_str(), Err(later[1].first).c_str());
    add("E7 dl_bandwidth_release_lag",
        "two 85 ms / 100 ms reservations that end after 50 ms, asked again at once and 300 ms later", buf,
        "the bandwidth of a DL thread that exits is returned at its 0-lag time, not at exit: a "
        "quick re-admission can see a transient EBUSY (EnterDeadline retries)");
  }
  if (json) std::printf("%s\n", report.dump(2).c_str());
  return 0;
}
