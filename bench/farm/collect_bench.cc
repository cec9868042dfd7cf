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
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include <benchmark/benchmark.h>

#include "api/client.h"
#include "navstack/rl/rollout.h"
#include "workers/worker/process.h"

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

std::string ReadText(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

template <typename F>
bool Eventually(F&& condition, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return condition();
}

void Run(std::vector<std::string> argv) {
  worker::SpawnOptions o;
  o.argv = std::move(argv);
  const auto status = worker::ChildProcess::Spawn(o).Wait(30s);
  if (!status || !status->ok()) throw std::runtime_error("command failed: " + o.argv.front() + " " + o.argv[1]);
}

// Network namespaces joined by veth pairs on a bridge in a hub namespace (as in
// tests/system/farm_netns_test.cc); removed on destruction.
class Namespaces {
 public:
  explicit Namespaces(const std::vector<std::string>& nodes) : tag_("eb" + std::to_string(getpid())) {
    const int p = static_cast<int>(getpid());
    const std::string subnet = "10." + std::to_string(150 + p % 100) + "." + std::to_string((p / 100) % 250) + ".";
    Run({"ip", "netns", "add", Ns("hub")});
    Run({"ip", "-n", Ns("hub"), "link", "add", "br0", "type", "bridge"});
    Run({"ip", "-n", Ns("hub"), "link", "set", "br0", "up"});
    int host = 1;
    for (const auto& node : nodes) {
      nodes_.push_back(node);
      addresses_[node] = subnet + std::to_string(host);
      const std::string a = tag_ + "a" + std::to_string(host), b = tag_ + "b" + std::to_string(host);
      ++host;
      Run({"ip", "netns", "add", Ns(node)});
      Run({"ip", "link", "add", a, "type", "veth", "peer", "name", b});
      Run({"ip", "link", "set", a, "netns", Ns(node)});
      Run({"ip", "link", "set", b, "netns", Ns("hub")});
      Run({"ip", "-n", Ns("hub"), "link", "set", b, "master", "br0", "up"});
      Run({"ip", "-n", Ns(node), "addr", "add", addresses_[node] + "/24", "dev", a});
      Run({"ip", "-n", Ns(node), "link", "set", a, "up"});
      Run({"ip", "-n", Ns(node), "link", "set", "lo", "up"});
    }
  }
  ~Namespaces() {
    for (const auto& node : nodes_) Del(node);
    Del("hub");
  }
  std::string Ns(const std::string& node) const { return tag_ + "-" + node; }
  const std::string& address(const std::string& node) const { return addresses_.at(node); }

 private:
  void Del(const std::string& node) {
    worker::SpawnOptions o;
    o.argv = {"ip", "netns", "del", Ns(node)};
    worker::ChildProcess::Spawn(o).Wait(30s);
  }
  std::string tag_;
  std::vector<std::string> nodes_;
  std::map<std::string, std::string> addresses_;
};

struct Farm {
  fs::path dir;
  std::vector<worker::ChildProcess> processes;
  std::string url;
};

// serve + N workers; with `ns`, each in its own namespace, else all on loopback.
void StartFarm(Farm* farm, int workers, const Namespaces* ns) {
  const std::string enavi = std::string(ENAVI_BINARY_DIR) + "/bin/enavi";
  const std::string domain = std::to_string(20 + getpid() % 100);
  const std::string partition = "bench-collect-" + std::to_string(getpid()) + "-" + std::to_string(workers);
  auto prefix = [&](const std::string& node) {
    return ns ? std::vector<std::string>{"ip", "netns", "exec", ns->Ns(node)} : std::vector<std::string>{};
  };
  auto spawn = [&](const std::string& node, std::vector<std::string> argv) {
    worker::SpawnOptions o;
    o.argv = prefix(node);
    o.argv.insert(o.argv.end(), argv.begin(), argv.end());
    o.stdout_file = o.stderr_file = farm->dir / (node + ".log");
    farm->processes.push_back(worker::ChildProcess::Spawn(o));
  };
  const fs::path ready = farm->dir / "ready";
  // The HTTP API listens where this process can reach it: the server's address in its namespace.
  std::vector<std::string> serve = {enavi, "serve", "--db", (farm->dir / "farm.db").string(), "--http",
                                    ns ? ns->address("server") + ":0" : "127.0.0.1:0", "--token", "bench",
                                    "--ready-file", ready.string(), "--domain", domain, "--partition", partition};
  if (ns) {
    serve.insert(serve.end(), {"--interface", ns->address("server")});
  } else {
    serve.push_back("--loopback");
  }
  spawn("server", serve);
  if (!Eventually([&] { return fs::exists(ready) && !ReadText(ready).empty(); }, 30s)) {
    throw std::runtime_error("server did not start: " + ReadText(farm->dir / "server.log"));
  }
  farm->url = ReadText(ready);
  while (!farm->url.empty() && farm->url.back() == '\n') farm->url.pop_back();
  for (int i = 0; i < workers; ++i) {
    const std::string node = "w" + std::to_string(i + 1);
    std::vector<std::string> argv = {enavi, "worker", "--id", node, "--slots", "1", "--domain", domain,
                                     "--partition", partition, "--spool", (farm->dir / node / "spool").string(),
                                     "--work-dir", (farm->dir / node / "work").string()};
    if (ns) {
      argv.insert(argv.end(), {"--interface", ns->address(node), "--server-host", ns->address("server")});
    } else {
      argv.push_back("--loopback");
    }
    spawn(node, argv);
  }
}

// Submits a collection job of `episodes` and waits for it; returns the transitions collected.
std::size_t Collect(api::FarmClient& client, const std::string& policy, int episodes, int first_seed) {
  std::string seeds = "[";
  for (int i = 0; i < episodes; ++i) seeds += (i ? ", " : "") + std::to_string(first_seed + i);
  const auto job = client.Submit("name: bench\nboards: [tx2]\nscenarios: [empty]\nmethods: [enavi]\n"
                                 "seeds: " + seeds + "]\ncollect: rollouts\nsample: true\npolicy: \"" +
                                     policy + "\"\n",
                                 "bench.yaml");
  if (!Eventually([&] { return client.Status(job.job_id).terminal(); }, 600s)) {
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
  Farm farm;
  farm.dir = fs::temp_directory_path() / ("bench-rl-collect-" + std::to_string(getpid()) + "-" +
                                          std::to_string(workers) + (netns ? "-ns" : ""));
  fs::remove_all(farm.dir);
  fs::create_directories(farm.dir);
  std::unique_ptr<Namespaces> ns;
  if (netns) {
    std::vector<std::string> nodes = {"server"};
    for (int i = 0; i < workers; ++i) nodes.push_back("w" + std::to_string(i + 1));
    ns = std::make_unique<Namespaces>(nodes);
  }
  std::size_t steps = 0, all_steps = 0;
  double seconds = 0;
  const double cpu0 = ChildrenCpuSeconds();
  try {
    StartFarm(&farm, workers, ns.get());
    auto work = [&] {
      api::FarmClient client(farm.url, "bench");
      if (!Eventually([&] { return static_cast<int>(client.Workers().size()) == workers; }, 60s)) {
        throw std::runtime_error("workers not discovered");
      }
      const std::string policy = client.UploadPolicy(
          ReadText(fs::path(ENAVI_SOURCE_DIR) / "navstack/rl/policies/enavi_default.json"));
      all_steps += Collect(client, policy, workers, 1000);  // warm-up: every worker caches the policy
      for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        steps = Collect(client, policy, kEpisodesPerWorker * workers, 1);
        all_steps += steps;
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        state.SetIterationTime(seconds);
      }
    };
    if (ns) {
      // This thread joins the server's namespace to reach its HTTP API.
      std::exception_ptr error;
      std::thread t([&] {
        try {
          const std::string path = "/var/run/netns/" + ns->Ns("server");
          const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
          if (fd < 0 || setns(fd, CLONE_NEWNET) != 0) throw std::runtime_error("setns failed");
          close(fd);
          work();
        } catch (...) {
          error = std::current_exception();
        }
      });
      t.join();
      if (error) std::rethrow_exception(error);
    } else {
      work();
    }
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
  for (auto& p : farm.processes) p.Signal(SIGKILL);
  for (auto& p : farm.processes) p.Wait(10s);  // reaped: their CPU time is counted
  farm.processes.clear();
  const double cpu = ChildrenCpuSeconds() - cpu0;
  ns.reset();
  fs::remove_all(farm.dir);
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
