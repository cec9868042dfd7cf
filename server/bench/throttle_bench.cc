#include "server/bench/throttle_bench.h"

#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <thread>

#include "navstack/runtime/sched_deadline.h"

namespace enavi::bench {
namespace {

constexpr int kMaxThreads = 64;

double Now(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// Shared between the benchmark and the child that runs the workload.
struct RunBlock {
  std::atomic<int> ready{0};
  std::atomic<int> go{0};
  pid_t tid[kMaxThreads] = {};
  double wall_start[kMaxThreads] = {};
  double wall_end[kMaxThreads] = {};
  double cpu[kMaxThreads] = {};
  int deadline_error[kMaxThreads] = {};  // errno of a refused SCHED_DEADLINE, 0 = granted / unused
  std::uint64_t sink = 0;
};

struct RunOutcome {
  bool ok = false;
  std::string message;
  std::vector<double> wall, cpu;
  double makespan = 0.0;
  std::int64_t nr_throttled = 0;
  std::string note;
};

// Forks a child with `threads` workload threads, optionally places it in `group` (each thread
// in its own per-core group) or gives each thread a SCHED_DEADLINE speed server, then starts all
// threads at once and collects per-thread wall and CPU times.
RunOutcome RunWorkload(int threads, std::int64_t units, emulation::EpisodeCgroup* group,
                       const navstack::DeadlineParams* server) {
  RunOutcome out;
  void* mem = mmap(nullptr, sizeof(RunBlock), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (mem == MAP_FAILED) {
    out.message = std::string("mmap: ") + std::strerror(errno);
    return out;
  }
  auto* block = new (mem) RunBlock();
  const pid_t child = fork();
  if (child < 0) {
    out.message = std::string("fork: ") + std::strerror(errno);
    munmap(mem, sizeof(RunBlock));
    return out;
  }
  if (child == 0) {
    std::vector<std::thread> pool;
    for (int i = 0; i < threads; ++i) {
      pool.emplace_back([block, i, units, server] {
        block->tid[i] = static_cast<pid_t>(gettid());
        if (server != nullptr) {
          navstack::DeadlineOptions o;
          o.ebusy_retries = 5;
          const navstack::DeadlineResult r = navstack::EnterDeadline(*server, o);
          block->deadline_error[i] = r.deadline ? 0 : r.error;
        }
        block->ready.fetch_add(1);
        while (block->go.load() == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
        const double c0 = Now(CLOCK_THREAD_CPUTIME_ID);
        block->wall_start[i] = Now(CLOCK_MONOTONIC);
        const std::uint64_t v = ThrottleWorkload(units);
        block->wall_end[i] = Now(CLOCK_MONOTONIC);
        block->cpu[i] = Now(CLOCK_THREAD_CPUTIME_ID) - c0;
        reinterpret_cast<std::atomic<std::uint64_t>*>(&block->sink)->fetch_xor(v);
      });
    }
    for (std::thread& t : pool) t.join();
    _exit(0);
  }

  auto abandon = [&](const std::string& message) {
    kill(child, SIGKILL);
    waitpid(child, nullptr, 0);
    munmap(mem, sizeof(RunBlock));
    out.message = message;
    return out;
  };
  for (int spins = 0; block->ready.load() < threads; ++spins) {
    if (spins > 10'000) return abandon("workload threads did not start within 10 s");
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (group != nullptr) {
    if (emulation::CgroupStatus s = group->AddProcess(child); !s.ok) return abandon(s.message);
    for (int i = 0; i < threads; ++i) {
      if (emulation::CgroupStatus s = group->AddThread(block->tid[i]); !s.ok) return abandon(s.message);
    }
  }
  const std::int64_t throttled0 = group != nullptr ? group->ReadCpuStat().nr_throttled : 0;
  block->go.store(1);
  int status = 0;
  waitpid(child, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return abandon("workload child failed");
  if (group != nullptr) out.nr_throttled = group->ReadCpuStat().nr_throttled - throttled0;

  double first = std::numeric_limits<double>::max(), last = 0.0;
  int refused = 0, refused_errno = 0;
  for (int i = 0; i < threads; ++i) {
    out.wall.push_back(block->wall_end[i] - block->wall_start[i]);
    out.cpu.push_back(block->cpu[i]);
    first = std::min(first, block->wall_start[i]);
    last = std::max(last, block->wall_end[i]);
    if (block->deadline_error[i] != 0) {
      ++refused;
      refused_errno = block->deadline_error[i];
    }
  }
  out.makespan = last - first;
  if (refused > 0) {
    out.note = std::to_string(refused) + " of " + std::to_string(threads) +
               " threads were refused SCHED_DEADLINE (" + std::strerror(refused_errno) +
               ") and ran unthrottled";
  }
  munmap(mem, sizeof(RunBlock));
  out.ok = true;
  return out;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

}  // namespace

std::uint64_t ThrottleWorkload(std::int64_t units) {
  // Register-only integer (xorshift) and floating-point (multiply-add) dependency chains: no
  // memory traffic, so the per-unit cost does not depend on caches shared with other work.
  std::uint64_t x = 0x9E3779B97F4A7C15ULL;
  double acc = 1.0;
  for (std::int64_t u = 0; u < units; ++u) {
    for (int i = 0; i < 1024; ++i) {
      x ^= x << 13;
      x ^= x >> 7;
      x ^= x << 17;
      acc = acc * 0.999999 + static_cast<double>(x & 0xffu) * 1e-6;
    }
  }
  return x ^ static_cast<std::uint64_t>(acc * 1e6);
}

ThrottleBenchResult RunThrottleBench(const std::string& board_id, const emulation::BoardCpu& board,
                                     const ThrottleBenchOptions& options) {
  ThrottleBenchResult result;
  result.board = board_id;
  result.mode = options.deadline_servers ? "deadline" : "cgroup";
  if (!(options.work_seconds > 0.0 && options.work_seconds <= 60.0)) {
    throw std::invalid_argument("throttle bench: work_seconds must be in (0, 60], got " +
                                std::to_string(options.work_seconds));
  }
  if (options.reference_repeats < 1 || options.reference_repeats > 20) {
    throw std::invalid_argument("throttle bench: reference_repeats must be in [1, 20], got " +
                                std::to_string(options.reference_repeats));
  }
  if (board.cores * 2 > kMaxThreads) {
    throw std::invalid_argument("throttle bench: at most " + std::to_string(kMaxThreads / 2) +
                                " board cores, got " + std::to_string(board.cores));
  }

  auto open = emulation::CgroupManager::Open(options.cgroup);
  if (!open.ok()) {
    result.message = open.error;
    return result;
  }
  emulation::CgroupManager& manager = *open.manager;
  result.host_cpus = manager.HostCpus();

  emulation::QuotaOptions q;
  q.period_us = options.period_us;
  q.dilation = options.dilation > 0.0
                   ? options.dilation
                   : emulation::MinimumDilation(board, result.host_cpus - options.cgroup.host_reserve_cpus);
  result.quota = emulation::ComputeBoardQuota(board, q);

  // Size the work: units per CPU-second of one unthrottled thread (this process).
  std::int64_t units = 16;
  double cpu = 0.0;
  while (true) {
    const double c0 = Now(CLOCK_THREAD_CPUTIME_ID);
    const std::uint64_t v = ThrottleWorkload(units);
    cpu = Now(CLOCK_THREAD_CPUTIME_ID) - c0;
    if (v == 42) result.message = "";  // keeps v alive
    if (cpu >= 0.2) break;
    units *= 2;
  }
  result.work_units = std::max<std::int64_t>(1, std::llround(units * options.work_seconds / cpu));

  // Reference: CPU time of one unthrottled thread, median of N runs.
  std::vector<double> ref_cpu, ref_wall;
  for (int r = 0; r < options.reference_repeats; ++r) {
    const RunOutcome ref = RunWorkload(1, result.work_units, nullptr, nullptr);
    if (!ref.ok) {
      result.message = "reference run: " + ref.message;
      return result;
    }
    ref_cpu.push_back(ref.cpu[0]);
    ref_wall.push_back(ref.wall[0]);
  }
  result.reference_cpu_s = Median(ref_cpu);
  result.reference_wall_s = Median(ref_wall);

  struct PhaseSpec {
    std::string name;
    int threads;
  };
  std::vector<PhaseSpec> specs{{"one_thread_per_board_core", board.cores}};
  if (options.extra_phases) {
    specs.push_back({"single_thread", 1});
    // A DL speed server per thread has no board-wide cap: oversubscription is cgroup-only.
    if (!options.deadline_servers) specs.push_back({"oversubscribed_2x", 2 * board.cores});
  }

  navstack::DeadlineParams server;
  if (options.deadline_servers) {
    server = navstack::SpeedServerParams(result.quota.CoreCpus(), result.quota.period_us * 1000);
  }
  for (const PhaseSpec& spec : specs) {
    auto created = manager.CreateEpisode(result.quota);
    if (!created.ok()) {
      result.message = created.refusal;
      return result;
    }
    // Speed servers replace the per-thread quota; the group then only holds the admission.
    const RunOutcome run = RunWorkload(spec.threads, result.work_units,
                                       options.deadline_servers ? nullptr : created.group.get(),
                                       options.deadline_servers ? &server : nullptr);
    if (options.deadline_servers) created.group->Remove();
    if (!run.ok) {
      result.message = spec.name + ": " + run.message;
      return result;
    }
    ThrottlePhase p;
    p.name = spec.name;
    p.threads = spec.threads;
    p.expected_slowdown = emulation::ExpectedSlowdown(result.quota, spec.threads, result.host_cpus);
    p.mean_wall_s = Mean(run.wall);
    p.makespan_s = run.makespan;
    p.mean_cpu_s = Mean(run.cpu);
    p.measured_slowdown = p.mean_wall_s / result.reference_cpu_s;
    p.relative_error = p.measured_slowdown / p.expected_slowdown - 1.0;
    for (double w : run.wall) {
      const double e = w / result.reference_cpu_s / p.expected_slowdown - 1.0;
      if (std::abs(e) > std::abs(p.max_thread_error)) p.max_thread_error = e;
    }
    p.nr_throttled = run.nr_throttled;
    p.note = run.note;
    p.thread_wall_s = run.wall;
    result.phases.push_back(p);
  }
  const ThrottlePhase& primary = result.phases.front();
  result.expected_slowdown = primary.expected_slowdown;
  result.measured_slowdown = primary.measured_slowdown;
  result.relative_error = primary.relative_error;
  result.ok = true;
  return result;
}

nlohmann::json ToJson(const ThrottleBenchResult& r) {
  nlohmann::json phases = nlohmann::json::array();
  for (const ThrottlePhase& p : r.phases) {
    phases.push_back({{"name", p.name},
                      {"threads", p.threads},
                      {"expected_slowdown", p.expected_slowdown},
                      {"measured_slowdown", p.measured_slowdown},
                      {"relative_error", p.relative_error},
                      {"max_thread_error", p.max_thread_error},
                      {"mean_wall_s", p.mean_wall_s},
                      {"makespan_s", p.makespan_s},
                      {"mean_cpu_s", p.mean_cpu_s},
                      {"nr_throttled", p.nr_throttled},
                      {"thread_wall_s", p.thread_wall_s},
                      {"note", p.note}});
  }
  return {{"ok", r.ok},
          {"message", r.message},
          {"board", r.board},
          {"mode", r.mode},
          {"cores", r.quota.cores},
          {"core_speed", r.quota.core_speed},
          {"dilation", r.quota.dilation},
          {"period_us", r.quota.period_us},
          {"board_quota_us", r.quota.board_quota_us},
          {"core_quota_us", r.quota.core_quota_us},
          {"host_cpus", r.host_cpus},
          {"workload", "xorshift64 + multiply-add loop, register-only, one process, 1024 steps/unit"},
          {"work_units", r.work_units},
          {"reference_cpu_s", r.reference_cpu_s},
          {"reference_wall_s", r.reference_wall_s},
          {"expected_slowdown_formula", "1 / min(speed / k, cores x speed / (k x threads), host_cpus / threads)"},
          {"expected_slowdown", r.expected_slowdown},
          {"measured_slowdown", r.measured_slowdown},
          {"relative_error", r.relative_error},
          {"phases", phases}};
}

}  // namespace enavi::bench
