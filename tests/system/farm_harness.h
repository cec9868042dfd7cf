#pragma once
// Harness for system tests: runs the real `enavi serve` and `enavi worker` processes (episodes
// by tests/system/fake_episode) on a private DDS domain and partition, and talks to the server
// over HTTP. Every process it starts is killed when the fixture ends, pass or fail, and dies with
// the test process if that is killed (PR_SET_PDEATHSIG).

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/client.h"
#include "workers/worker/process.h"

namespace enavi::testing {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

inline fs::path EnaviBinary() { return fs::path(ENAVI_BINARY_DIR) / "bin/enavi"; }
inline fs::path FakeEpisode() { return fs::path(ENAVI_BINARY_DIR) / "tests/fake_episode"; }

/// The episode command of the farm tests: tests/system/fake_episode, or the command in
/// ENAVI_SYSTEM_EPISODE_CMD (e.g. "build/bin/enavi fly") to run them on real episodes.
inline std::string EpisodeCommand() {
  const char* cmd = std::getenv("ENAVI_SYSTEM_EPISODE_CMD");
  return cmd != nullptr && *cmd != '\0' ? std::string(cmd) : FakeEpisode().string();
}

/// Polls until `condition` holds or `timeout` passes.
template <typename F>
bool Eventually(F&& condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(50ms);
  }
  return condition();
}

inline std::string ReadText(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class FarmFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() / ("enavi-system-" + std::to_string(getpid()) + "-" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // Unique per test process; the partition keeps us apart even if a domain id is shared.
    domain_ = 10 + static_cast<int>(getpid() % 100);
    partition_ = "system-" + std::to_string(getpid()) + "-" + name;
  }

  void TearDown() override {
    // Kill everything first (the destructors of ChildProcess do it too); then show the logs of a
    // failed test, so a CI failure explains itself.
    for (auto& [name, p] : processes_) p.Signal(SIGKILL);
    processes_.clear();
    if (HasFailure()) {
      for (const auto& entry : fs::directory_iterator(dir_)) {
        if (entry.path().extension() == ".log") {
          std::string text = ReadText(entry.path());
          if (text.size() > 4000) text = "..." + text.substr(text.size() - 4000);
          std::cerr << "==== " << entry.path().filename().string() << " ====\n" << text << "\n";
        }
      }
    }
    // ENAVI_KEEP_SYSTEM_LOGS=1 keeps the directory (logs, database) for a look afterwards.
    if (const char* keep = std::getenv("ENAVI_KEEP_SYSTEM_LOGS"); keep && *keep == '1') {
      std::cerr << "kept " << dir_ << "\n";
    } else {
      fs::remove_all(dir_);
    }
  }

  // Prefix for commands run elsewhere (ip netns exec NS); empty: here.
  virtual std::vector<std::string> Prefix(const std::string& /*node*/) const { return {}; }
  // DDS network flags for a node (loopback by default).
  virtual std::vector<std::string> BusArgs(const std::string& /*node*/) const { return {"--loopback"}; }

  worker::ChildProcess& Start(const std::string& name, std::vector<std::string> argv,
                              std::vector<std::string> env = {}, std::string log = "") {
    worker::SpawnOptions o;
    o.argv = Prefix(name);
    o.argv.insert(o.argv.end(), argv.begin(), argv.end());
    o.env = std::move(env);
    o.stdout_file = dir_ / ((log.empty() ? name : log) + ".log");
    o.stderr_file = o.stdout_file;
    auto [it, inserted] = processes_.insert_or_assign(name, worker::ChildProcess::Spawn(o));
    return it->second;
  }

  /// Starts `enavi serve` on the database in the test directory; returns its URL.
  std::string StartServer(const std::string& node = "server") {
    const std::string run = std::to_string(server_starts_++);
    const fs::path ready = dir_ / ("ready-" + run);
    std::vector<std::string> argv = {EnaviBinary().string(), "serve", "--db",
                                     (dir_ / "farm.db").string(), "--http", "127.0.0.1:0",
                                     "--ready-file", ready.string(), "--domain",
                                     std::to_string(domain_), "--partition", partition_,
                                     // The fake episode's knobs are not `enavi fly` tunables.
                                     "--unchecked-overrides", "fake."};
    for (const auto& a : BusArgs(node)) argv.push_back(a);
    Start(node, argv, {}, node + "-" + run);  // one log per start
    EXPECT_TRUE(Eventually([&] { return fs::exists(ready); }, 30s)) << "server did not start";
    std::string url = ReadText(ready);
    while (!url.empty() && url.back() == '\n') url.pop_back();
    url_ = url;
    return url;
  }

  /// Starts `enavi worker`; fake episodes take `episode_s` seconds each. `command`: the episode
  /// command (default EpisodeCommand()).
  worker::ChildProcess& StartWorker(const std::string& name, int slots = 1,
                                    double episode_s = 1.0, std::string command = "") {
    std::vector<std::string> argv = {EnaviBinary().string(), "worker", "--id", name, "--slots",
                                     std::to_string(slots), "--domain", std::to_string(domain_),
                                     "--partition", partition_, "--spool",
                                     (dir_ / name / "spool").string(), "--work-dir",
                                     (dir_ / name / "work").string(), "--episode-cmd",
                                     command.empty() ? EpisodeCommand() : command};
    for (const auto& a : BusArgs(name)) argv.push_back(a);
    // Through the environment, not the job spec: a real `enavi fly` ignores these.
    std::vector<std::string> env = {"FAKE_EPISODE_LOG=" + (dir_ / "episodes.txt").string(),
                                    "FAKE_EPISODE_SLEEP_S=" + std::to_string(episode_s)};
    return Start(name, argv, env);
  }

  worker::ChildProcess& Process(const std::string& name) { return processes_.at(name); }

  /// A job of 2 boards x 1 scenario x 2 methods x `seeds` seeds.
  static std::string Job(int seeds) {
    return "name: system\nboards: [tx2, pi4b]\nscenarios: [s1]\nmethods: [baseline, enavi]\n"
           "seeds: " + std::to_string(seeds) + "\n";
  }

  /// Checks a finished job: exactly `n` results, one per episode, matching the matrix.
  void ExpectExactlyOneResultPerEpisode(api::FarmClient& client, const std::string& job, int n) {
    const api::JobProgress p = client.Status(job);
    EXPECT_EQ(p.state, "done");
    EXPECT_EQ(p.done, n);
    EXPECT_EQ(p.failed, 0);
    const nlohmann::json results = client.Results(job);
    ASSERT_EQ(results.size(), static_cast<std::size_t>(n));
    std::set<std::string> ids;
    std::set<std::tuple<std::string, std::string, int>> cells;
    for (const auto& r : results) {
      ids.insert(r["episode_id"].get<std::string>());
      cells.insert({r["board"].get<std::string>(), r["method"].get<std::string>(),
                    r["seed"].get<int>()});
    }
    EXPECT_EQ(ids.size(), static_cast<std::size_t>(n)) << "duplicate results";
    EXPECT_EQ(cells.size(), static_cast<std::size_t>(n)) << "results do not cover the matrix";
  }

  fs::path dir_;
  int domain_ = 0;
  std::string partition_;
  std::string url_;
  int server_starts_ = 0;
  std::map<std::string, worker::ChildProcess> processes_;
};

}  // namespace enavi::testing
