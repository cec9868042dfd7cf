// RL data collection throughput: transitions (E-Navi decisions with their rewards) collected per
// second by a collection job on the real farm processes: `enavi serve` and N `enavi worker`s
// (one slot each) flying real episodes of the short `empty` world with the shipped policy,
// rollouts over DDS into SQLite. The clock runs from the job's submission to its last stored
// rollout. Loopback with 1 and 2 workers, and 4 workers each in its own network namespace (root
// only) with the server in a fifth, as separate hosts would be.
//
// The nav variants collect the learned method's rollouts instead (64x48 depth images, 30
// decisions a second of flight): a zero-weight network with exploration noise (log_std -1)
// hovering and drifting in a sparse forest for 10 s per episode, so every episode records about
// 300 decisions; compare with the in-process environment's steps/s (bench/rl/nav_env_bench.py).
//
// Reported against the 1-worker figure of the same run: scaling = rate(N) / (N x rate(1)).
// Goal: >= 0.9 from 1 to 2 workers (needs 2 idle cores: every worker is CPU-bound). Because wall
// rates only mean something on an idle machine, transitions_per_cpu_s also reports transitions
// per CPU second of all the farm's processes (server, workers, episodes; start-up and warm-up
// included): if it stays flat from 1 to N workers, the farm adds no per-worker overhead and the
// wall rate scales with the cores given to it.
//
//   bench_rl_collect [--benchmark_filter=...]
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>

#include <benchmark/benchmark.h>

#include "api/client.h"
#include "bench/farm/farm_processes.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/nav_rollout.h"

namespace enavi {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kEpisodesPerWorker = 8;

enum class Kind { kFrequency, kNav };
double one_worker_rate[2] = {0, 0};  // transitions/s with one worker, this run, per kind

// The job and its policy of each kind.
std::string JobYaml(Kind kind) {
  if (kind == Kind::kNav)
    return "boards: [pi4b]\nscenarios: [forest]\nworld_params: {density: \"2\", length: \"20\"}\n"
           "methods: [learned]\ntimeout_s: 10\n";
  return "boards: [tx2]\nscenarios: [empty]\nmethods: [enavi]\n";
}

std::string PolicyText(Kind kind) {
  if (kind == Kind::kNav) {
    navstack::rl::NavPolicyNet net = navstack::rl::DefaultNavArchitecture(64, 48);
    net.set_log_std({-1, -1, -1, -1});
    return navstack::rl::NavPolicyToJson(net).dump();
  }
  return bench::ReadText(fs::path(ENAVI_SOURCE_DIR) / "navstack/rl/policies/enavi_default.json");
}

// CPU seconds of this process's waited-for descendants so far.
double ChildrenCpuSeconds() {
  rusage ru{};
  getrusage(RUSAGE_CHILDREN, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// Submits a collection job of `episodes` and waits for it; returns the transitions collected.
std::size_t Collect(api::FarmClient& client, Kind kind, const std::string& policy, int episodes, int first_seed) {
  std::string seeds = "[";
  for (int i = 0; i < episodes; ++i) seeds += (i ? ", " : "") + std::to_string(first_seed + i);
  const auto job = client.Submit("name: bench\n" + JobYaml(kind) + "seeds: " + seeds +
                                     "]\ncollect: rollouts\nsample: true\npolicy: \"" + policy + "\"\n",
                                 "bench.yaml");
  if (!bench::Eventually([&] { return client.Status(job.job_id).terminal(); }, 600s)) {
    throw std::runtime_error("collection job did not finish");
  }
  std::size_t steps = 0;
  for (const auto& r : client.Rollouts(job.job_id)) {
    steps += navstack::rl::CheckRolloutBlob(r.rollout, r.episode_id);
  }
  return steps;
}

void BM_Collect(benchmark::State& state, bool netns, Kind kind) {
  const int workers = static_cast<int>(state.range(0));
  if (netns && geteuid() != 0) {
    state.SkipWithError("needs root for network namespaces");
    return;
  }
  const fs::path dir = fs::temp_directory_path() / ("bench-rl-collect-" + std::to_string(getpid()) +
                                                  "-" + std::to_string(workers) + (netns ? "-ns" : ""));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::unique_ptr<bench::Namespaces> ns;
  if (netns) {
    std::vector<std::string> nodes = {"server"};
    for (int i = 0; i < workers; ++i) nodes.push_back("w" + std::to_string(i + 1));
    ns = std::make_unique<bench::Namespaces>("eb" + std::to_string(getpid()), nodes, 150);
  }
  std::size_t steps = 0, all_steps = 0;
  double seconds = 0;
  const double cpu0 = ChildrenCpuSeconds();
  try {
    bench::FarmLaunch launch;
    launch.workers = workers;
    launch.partition = "bench-collect-" + std::to_string(getpid()) + "-" + std::to_string(workers);
    bench::Farm farm(dir, launch, ns.get());
    farm.WithApi([&] {
      api::FarmClient client(farm.url(), "bench");
      if (!bench::Eventually([&] { return static_cast<int>(client.Workers().size()) == workers; }, 60s)) {
        throw std::runtime_error("workers not discovered");
      }
      const std::string policy = client.UploadPolicy(PolicyText(kind));
      all_steps += Collect(client, kind, policy, workers, 1000);  // warm-up: every worker caches the policy
      for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        steps = Collect(client, kind, policy, kEpisodesPerWorker * workers, 1);
        all_steps += steps;
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        state.SetIterationTime(seconds);
      }
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
  const double cpu = ChildrenCpuSeconds() - cpu0;  // the farm is reaped: its CPU time counts
  ns.reset();
  fs::remove_all(dir);
  if (seconds <= 0) return;
  const double rate = static_cast<double>(steps) / seconds;
  double& reference = one_worker_rate[static_cast<int>(kind)];
  if (workers == 1 && !netns) reference = rate;
  state.counters["transitions_per_s"] = rate;
  state.counters["episodes_per_s"] = kEpisodesPerWorker * workers / seconds;
  state.counters["transitions"] = static_cast<double>(steps);
  if (cpu > 0) state.counters["transitions_per_cpu_s"] = static_cast<double>(all_steps) / cpu;
  if (reference > 0) state.counters["scaling"] = rate / (workers * reference);
}

BENCHMARK_CAPTURE(BM_Collect, loopback, false, Kind::kFrequency)
    ->Arg(1)->Arg(2)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(BM_Collect, netns, true, Kind::kFrequency)
    ->Arg(4)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(BM_Collect, nav_loopback, false, Kind::kNav)
    ->Arg(1)->Arg(2)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace enavi

BENCHMARK_MAIN();
