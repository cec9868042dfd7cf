// RL data collection throughput: transitions (E-Navi decisions with their rewards) collected per
// second by a collection job on the real farm processes: `enavi serve` and N `enavi worker`s
// (one slot each) flying real episodes of the short `empty` world with the shipped policy,
// rollouts over DDS into SQLite. The clock runs from the job's submission to its last stored
// rollout. Loopback with 1 and 2 workers, and 4 workers each in its own network namespace (root
// only) with the server in a fifth, as separate hosts would be.
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
#include "navstack/rl/rollout.h"

namespace enavi {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kEpisodesPerWorker = 8;
double one_worker_rate = 0;  // transitions/s with one worker, this run

// CPU seconds of this process's waited-for descendants so far.
double ChildrenCpuSeconds() {
  rusage ru{};
  getrusage(RUSAGE_CHILDREN, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// Submits a collection job of `episodes` and waits for it; returns the transitions collected.
std::size_t Collect(api::FarmClient& client, const std::string& policy, int episodes, int first_seed) {
  std::string seeds = "[";
  for (int i = 0; i < episodes; ++i) seeds += (i ? ", " : "") + std::to_string(first_seed + i);
  const auto job = client.Submit("name: bench\nboards: [tx2]\nscenarios: [empty]\nmethods: [enavi]\n"
                                 "seeds: " + seeds + "]\ncollect: rollouts\nsample: true\npolicy: \"" +
                                     policy + "\"\n",
                                 "bench.yaml");
  if (!bench::Eventually([&] { return client.Status(job.job_id).terminal(); }, 600s)) {
    throw std::runtime_error("collection job did not finish");
  }
  std::size_t steps = 0;
  for (const auto& r : client.Rollouts(job.job_id)) {
    steps += navstack::rl::DecodeRollout(r.rollout, r.episode_id).steps.size();
  }
  return steps;
}

void BM_Collect(benchmark::State& state, bool netns) {
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
      const std::string policy = client.UploadPolicy(
          bench::ReadText(fs::path(ENAVI_SOURCE_DIR) / "navstack/rl/policies/enavi_default.json"));
      all_steps += Collect(client, policy, workers, 1000);  // warm-up: every worker caches the policy
      for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        steps = Collect(client, policy, kEpisodesPerWorker * workers, 1);
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
  if (workers == 1 && !netns) one_worker_rate = rate;
  state.counters["transitions_per_s"] = rate;
  state.counters["episodes_per_s"] = kEpisodesPerWorker * workers / seconds;
  state.counters["transitions"] = static_cast<double>(steps);
  if (cpu > 0) state.counters["transitions_per_cpu_s"] = static_cast<double>(all_steps) / cpu;
  if (one_worker_rate > 0) state.counters["scaling"] = rate / (workers * one_worker_rate);
}

BENCHMARK_CAPTURE(BM_Collect, loopback, false)->Arg(1)->Arg(2)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(BM_Collect, netns, true)->Arg(4)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace enavi

BENCHMARK_MAIN();
