// How the farm scales with its workers: `enavi serve` in one network namespace and 1, 2, 4, 8
// `enavi worker`s, each in a namespace of its own (separate hosts to DDS, unicast discovery).
// The episodes are tests/system/fake_episode, which sleeps kEpisodeS and costs almost no CPU, so
// what is measured is the farm: assignment, result ingestion, DDS, the workers' child processes.
//
// Counters, over the window from submission to the last stored result (discovery_s: from
// starting the processes until the server lists every worker):
//   assignments_per_s, results_per_s   from the server's own counters (GET /api/health)
//   ideal_per_s                        workers x slots / kEpisodeS: a farm that costs nothing
//   efficiency                         results_per_s / ideal_per_s (the reference, same run)
//   overhead_ms                        slot time per episode not spent in the episode:
//                                      workers x slots x window / episodes - kEpisodeS
//                                      (assignment latency, ack, spawning the episode process)
//   server_cpu_pct                     CPU of `enavi serve` over the window, % of one core
//   server_cpu_ms_per_ep               the same per stored result
//   server_idle_cpu_pct                CPU of `enavi serve` with the workers connected, idle
//   server_udp_out_per_ep, _in_per_ep UDP datagrams the server sends and receives per result
//                                      (DDS without multicast: one copy per matched reader)
//   workers_cpu_pct, episodes_cpu_pct  CPU of the `enavi worker`s and of their (reaped)
//                                      episode processes over the window, % of one core
//   host_busy_pct                      CPU of the whole machine over the window, % of all cores
// Root only (network namespaces). docs/farm.md has the table and what limits it.
//
//   bench_farm_scale [--benchmark_filter=...]
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include <benchmark/benchmark.h>

#include "api/client.h"
#include "bench/farm/farm_processes.h"

namespace enavi {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kSlots = 4;                 // per worker
constexpr double kEpisodeS = 0.25;        // fake episode length
constexpr int kEpisodesPerSlot = 12;      // per measured job
constexpr auto kIdleWindow = std::chrono::seconds(5);

// CPU seconds of a process (utime + stime, /proc/PID/stat fields 14-15) and of its reaped
// children (cutime + cstime, fields 16-17: a worker's episode processes).
struct Cpu {
  double self = 0, children = 0;
};
Cpu ProcessCpu(pid_t pid) {
  std::istringstream in(bench::ReadText("/proc/" + std::to_string(pid) + "/stat"));
  std::string field;
  // Field 2 (comm) is parenthesised and may hold spaces: skip past its closing parenthesis.
  std::getline(in, field, ')');
  Cpu cpu;
  const double tick = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  for (int i = 3; i <= 17 && in >> field; ++i) {
    if (i == 14 || i == 15) cpu.self += std::stod(field) * tick;
    if (i == 16 || i == 17) cpu.children += std::stod(field) * tick;
  }
  return cpu;
}

Cpu WorkersCpu(const bench::Farm& farm) {
  Cpu sum;
  for (pid_t pid : farm.worker_pids()) {
    const Cpu c = ProcessCpu(pid);
    sum.self += c.self;
    sum.children += c.children;
  }
  return sum;
}

// UDP datagrams in and out of a process's network namespace (/proc/PID/net/snmp, "Udp:" rows):
// the server alone in its namespace, so its DDS traffic.
std::pair<double, double> UdpDatagrams(pid_t pid) {
  std::istringstream in(bench::ReadText("/proc/" + std::to_string(pid) + "/net/snmp"));
  std::string names, values;
  while (std::getline(in, names) && std::getline(in, values)) {
    if (names.rfind("Udp:", 0) != 0) continue;
    std::istringstream n(names), v(values);
    std::string name, value;
    std::map<std::string, double> row;
    while (n >> name && v >> value) row[name] = name == "Udp:" ? 0 : std::stod(value);
    return {row["InDatagrams"], row["OutDatagrams"]};
  }
  throw std::runtime_error("no Udp row in /proc/" + std::to_string(pid) + "/net/snmp");
}

// Busy and total jiffies of all CPUs (/proc/stat, first line).
std::pair<double, double> HostJiffies() {
  std::istringstream in(bench::ReadText("/proc/stat"));
  std::string cpu;
  in >> cpu;
  double v = 0, total = 0, idle = 0;
  for (int i = 0; i < 8 && in >> v; ++i) {
    total += v;
    if (i == 3 || i == 4) idle += v;  // idle, iowait
  }
  return {total - idle, total};
}

void BM_Scale(benchmark::State& state) {
  const int workers = static_cast<int>(state.range(0));
  if (geteuid() != 0) {
    state.SkipWithError("needs root for network namespaces");
    return;
  }
  const std::string tag = "enavi-scale-" + std::to_string(getpid()) + "-" + std::to_string(workers);
  const fs::path dir = fs::temp_directory_path() / tag;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<std::string> nodes = {"server"};
  for (int i = 0; i < workers; ++i) nodes.push_back("w" + std::to_string(i + 1));
  try {
    bench::Namespaces ns(tag, nodes, 200);
    bench::FarmLaunch launch;
    launch.workers = workers;
    launch.slots = kSlots;
    launch.partition = tag;
    launch.episode_cmd = std::string(ENAVI_BINARY_DIR) + "/tests/fake_episode";
    launch.worker_env = {"FAKE_EPISODE_SLEEP_S=" + std::to_string(kEpisodeS)};
    const auto started = std::chrono::steady_clock::now();
    bench::Farm farm(dir, launch, &ns);
    farm.WithApi([&] {
      api::FarmClient client(farm.url(), "bench");
      if (!bench::Eventually([&] { return static_cast<int>(client.Workers().size()) == workers; }, 60s)) {
        throw std::runtime_error("workers not discovered");
      }
      const double discovery_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      // The cost of being connected: the server's CPU with the workers idle (heartbeats).
      const double idle0 = ProcessCpu(farm.server_pid()).self;
      std::this_thread::sleep_for(kIdleWindow);
      const double idle_cpu = ProcessCpu(farm.server_pid()).self - idle0;
      const int episodes = workers * kSlots * kEpisodesPerSlot;
      int first_seed = 1;
      for (auto _ : state) {
        const nlohmann::json before = client.Health()["stats"];
        const double server_cpu0 = ProcessCpu(farm.server_pid()).self;
        const Cpu workers0 = WorkersCpu(farm);
        const auto udp0 = UdpDatagrams(farm.server_pid());
        const auto host0 = HostJiffies();
        const auto t0 = std::chrono::steady_clock::now();
        const auto job = client.Submit("name: scale\nboards: [tx2]\nscenarios: [s1]\nmethods: [baseline]\n"
                                       "seeds: [" + [&] {
                                         std::string s;
                                         for (int i = 0; i < episodes; ++i) s += (i ? "," : "") + std::to_string(first_seed + i);
                                         return s;
                                       }() + "]\n",
                                       "scale.yaml");
        first_seed += episodes;
        if (!bench::Eventually([&] { return client.Status(job.job_id).terminal(); }, 600s)) {
          throw std::runtime_error("job did not finish");
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const auto host1 = HostJiffies();
        const double server_cpu = ProcessCpu(farm.server_pid()).self - server_cpu0;
        const Cpu workers1 = WorkersCpu(farm);
        const auto udp1 = UdpDatagrams(farm.server_pid());
        const nlohmann::json after = client.Health()["stats"];
        const api::JobProgress p = client.Status(job.job_id);
        if (p.done != episodes) throw std::runtime_error("only " + std::to_string(p.done) + " episodes done");
        state.SetIterationTime(seconds);
        const double assigned = after["assignments"].get<double>() - before["assignments"].get<double>();
        const double stored = after["results_stored"].get<double>() - before["results_stored"].get<double>();
        const double ideal = workers * kSlots / kEpisodeS;
        state.counters["assignments_per_s"] = assigned / seconds;
        state.counters["results_per_s"] = stored / seconds;
        state.counters["ideal_per_s"] = ideal;
        state.counters["discovery_s"] = discovery_s;
        state.counters["efficiency"] = stored / seconds / ideal;
        state.counters["overhead_ms"] = 1000 * (workers * kSlots * seconds / episodes - kEpisodeS);
        state.counters["server_cpu_pct"] = 100 * server_cpu / seconds;
        state.counters["server_idle_cpu_pct"] = 100 * idle_cpu / std::chrono::duration<double>(kIdleWindow).count();
        state.counters["server_cpu_ms_per_ep"] = 1000 * server_cpu / stored;
        state.counters["server_udp_out_per_ep"] = (udp1.second - udp0.second) / stored;
        state.counters["server_udp_in_per_ep"] = (udp1.first - udp0.first) / stored;
        state.counters["workers_cpu_pct"] = 100 * (workers1.self - workers0.self) / seconds;
        state.counters["episodes_cpu_pct"] = 100 * (workers1.children - workers0.children) / seconds;
        state.counters["host_busy_pct"] = 100 * (host1.first - host0.first) / (host1.second - host0.second);
      }
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
  if (!state.error_occurred()) fs::remove_all(dir);  // kept for a look after an error
}

BENCHMARK(BM_Scale)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace enavi

BENCHMARK_MAIN();
