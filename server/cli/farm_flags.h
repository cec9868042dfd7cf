#pragma once
// Flags and process plumbing the farm's subcommands share: DDS bus selection, logging, and
// SIGINT/SIGTERM handling for the daemons.

#include <atomic>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "api/farm_bus.h"

namespace enavi::cli {

/// DDS flags: --domain, --partition, --peers, --interface, --dds-config, --loopback.
struct BusFlags {
  int domain = 0;
  std::string partition = "enavi";
  std::vector<std::string> peers;
  std::string interface;
  std::string dds_config;
  bool loopback = false;
};
void AddBusFlags(CLI::App* app, BusFlags* flags);

/// Bus options from the flags. Without --peers/--interface/--dds-config/--loopback:
/// CYCLONEDDS_URI when set, else the private loopback configuration (one machine).
/// @throws std::invalid_argument naming the flag on bad values.
api::BusOptions ResolveBus(const BusFlags& flags);

/// Logs to stderr with timestamps; `verbose` adds debug messages.
void SetupLogging(bool verbose);

/// Blocks SIGINT and SIGTERM in this thread (and so in every thread started afterwards) and
/// hands them to a watcher. Construct it first thing in a daemon's handler.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  /// Blocks until SIGINT or SIGTERM arrives; returns the signal.
  int Wait();
  /// Calls on_signal(n) (n = 1, 2, ...) from a background thread for each signal.
  void Watch(std::function<void(int)> on_signal);

 private:
  std::atomic<bool> done_{false};
  std::thread watcher_;
};

/// Without --episode-cmd the farm runs `enavi episode`: refuse to start when this build has no `episode`
/// subcommand, instead of failing every episode three times.
/// @throws std::runtime_error naming the missing command.
void RequireEpisodeUnlessEpisodeCmd(const CLI::App& root, const std::string& episode_cmd);

/// Splits "host:port" ("[v6]:port"); @throws std::invalid_argument naming `flag`.
std::pair<std::string, int> ParseHostPort(const std::string& text, const std::string& flag);

}  // namespace enavi::cli
