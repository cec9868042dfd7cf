#pragma once
// The real farm processes for the farm benchmarks: `enavi serve` and N `enavi worker`s, on
// loopback or each in its own network namespace (veth pairs on a bridge in a hub namespace, as
// in tests/system/farm_netns_test.cc). Everything started is killed and removed on destruction.

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "workers/worker/process.h"

namespace enavi::bench {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

inline std::string ReadText(const fs::path& p) {
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

inline void Run(std::vector<std::string> argv) {
  worker::SpawnOptions o;
  o.argv = std::move(argv);
  const auto status = worker::ChildProcess::Spawn(o).Wait(30s);
  if (!status || !status->ok()) throw std::runtime_error("command failed: " + o.argv.front() + " " + o.argv[1]);
}

/// Network namespaces named `tag`-NODE, one per node, on one bridge; removed on destruction.
class Namespaces {
 public:
  Namespaces(const std::string& tag, const std::vector<std::string>& nodes, int subnet_base)
      : tag_(tag) {
    const int p = static_cast<int>(getpid());
    const std::string subnet = "10." + std::to_string(subnet_base + p % 50) + "." +
                               std::to_string((p / 50) % 250) + ".";
    Run({"ip", "netns", "add", Ns("hub")});
    Run({"ip", "-n", Ns("hub"), "link", "add", "br0", "type", "bridge"});
    Run({"ip", "-n", Ns("hub"), "link", "set", "br0", "up"});
    int host = 1;
    for (const auto& node : nodes) {
      nodes_.push_back(node);
      addresses_[node] = subnet + std::to_string(host);
      // veth names are at most 15 characters: a short per-process prefix and the host number.
      const std::string veth = "v" + std::to_string(p % 100000) + "_";
      const std::string a = veth + "a" + std::to_string(host), b = veth + "b" + std::to_string(host);
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
  Namespaces(const Namespaces&) = delete;
  Namespaces& operator=(const Namespaces&) = delete;

  std::string Ns(const std::string& node) const { return tag_ + "-" + node; }
  const std::string& address(const std::string& node) const { return addresses_.at(node); }

  /// Runs `fn` on a thread that has joined `node`'s namespace (to reach the server's HTTP API).
  void In(const std::string& node, const std::function<void()>& fn) const {
    std::exception_ptr error;
    std::thread t([&] {
      try {
        const std::string path = "/var/run/netns/" + Ns(node);
        const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0 || setns(fd, CLONE_NEWNET) != 0) throw std::runtime_error("setns " + path + " failed");
        close(fd);
        fn();
      } catch (...) {
        error = std::current_exception();
      }
    });
    t.join();
    if (error) std::rethrow_exception(error);
  }

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

/// What to start.
struct FarmLaunch {
  int workers = 1;
  int slots = 1;                        ///< per worker
  std::string partition;                ///< unique per farm
  std::string episode_cmd;              ///< empty: enavi fly
  std::vector<std::string> worker_env;  ///< NAME=value for every worker (and its episodes)
  std::vector<std::string> serve_args;  ///< further `enavi serve` flags
};

/// A running farm: server node "server", workers "w1".."wN". With `ns`, each node in its own
/// namespace, else all on loopback. The server's HTTP API needs token "bench".
class Farm {
 public:
  Farm(fs::path dir, const FarmLaunch& launch, const Namespaces* ns) : dir_(std::move(dir)), ns_(ns) {
    const std::string enavi = std::string(ENAVI_BINARY_DIR) + "/bin/enavi";
    const std::string domain = std::to_string(20 + getpid() % 100);
    const fs::path ready = dir_ / "ready";
    // The HTTP API listens where the caller can reach it: the server's address in its namespace.
    std::vector<std::string> serve = {enavi, "serve", "--db", (dir_ / "farm.db").string(), "--http",
                                      ns ? ns->address("server") + ":0" : "127.0.0.1:0", "--token",
                                      "bench", "--ready-file", ready.string(), "--domain", domain,
                                      "--partition", launch.partition};
    serve.insert(serve.end(), launch.serve_args.begin(), launch.serve_args.end());
    if (ns) {
      serve.insert(serve.end(), {"--interface", ns->address("server")});
    } else {
      serve.push_back("--loopback");
    }
    Spawn("server", serve, {});
    if (!Eventually([&] { return fs::exists(ready) && !ReadText(ready).empty(); }, 30s)) {
      throw std::runtime_error("server did not start: " + ReadText(dir_ / "server.log"));
    }
    url_ = ReadText(ready);
    while (!url_.empty() && url_.back() == '\n') url_.pop_back();
    for (int i = 0; i < launch.workers; ++i) {
      const std::string node = "w" + std::to_string(i + 1);
      std::vector<std::string> argv = {enavi, "worker", "--id", node, "--slots",
                                       std::to_string(launch.slots), "--domain", domain,
                                       "--partition", launch.partition, "--spool",
                                       (dir_ / node / "spool").string(), "--work-dir",
                                       (dir_ / node / "work").string()};
      if (!launch.episode_cmd.empty()) argv.insert(argv.end(), {"--episode-cmd", launch.episode_cmd});
      if (ns) {
        argv.insert(argv.end(), {"--interface", ns->address(node), "--server-host", ns->address("server")});
      } else {
        argv.push_back("--loopback");
      }
      Spawn(node, argv, launch.worker_env);
    }
  }
  /// Kills and reaps every process (so their CPU time counts in RUSAGE_CHILDREN).
  ~Farm() {
    for (auto& p : processes_) p.Signal(SIGKILL);
    for (auto& p : processes_) p.Wait(10s);
  }
  Farm(const Farm&) = delete;
  Farm& operator=(const Farm&) = delete;

  const std::string& url() const { return url_; }
  pid_t server_pid() const { return processes_.front().pid(); }
  std::vector<pid_t> worker_pids() const {
    std::vector<pid_t> out;
    for (std::size_t i = 1; i < processes_.size(); ++i) out.push_back(processes_[i].pid());
    return out;
  }
  /// Runs `fn` where the server's HTTP API is reachable.
  void WithApi(const std::function<void()>& fn) const { ns_ ? ns_->In("server", fn) : fn(); }

 private:
  void Spawn(const std::string& node, const std::vector<std::string>& argv,
             std::vector<std::string> env) {
    worker::SpawnOptions o;
    if (ns_) o.argv = {"ip", "netns", "exec", ns_->Ns(node)};
    o.argv.insert(o.argv.end(), argv.begin(), argv.end());
    o.env = std::move(env);
    o.stdout_file = o.stderr_file = dir_ / (node + ".log");
    processes_.push_back(worker::ChildProcess::Spawn(o));
  }

  fs::path dir_;
  const Namespaces* ns_;
  std::vector<worker::ChildProcess> processes_;
  std::string url_;
};

}  // namespace enavi::bench
