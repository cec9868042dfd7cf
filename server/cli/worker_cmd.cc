// enavi worker: the farm worker daemon.
#include <algorithm>
#include <cstdlib>
#include <memory>

#include <spdlog/spdlog.h>

#include "server/cli/commands.h"
#include "server/cli/farm_flags.h"
#include "server/cli/registry_help.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_config.h"
#include "workers/worker/process.h"
#include "workers/worker/worker.h"

namespace enavi::cli {
namespace {

struct WorkerFlags {
  int slots = 1;
  std::string id;
  std::vector<std::string> boards, clocks;
  std::string calibration_id;
  std::string episode_cmd;
  double episode_timeout_s = 3600;
  std::int64_t episode_memory_mb = 8192;
  std::int64_t episode_cpu_s = 0;
  std::string spool, work_dir;
  bool keep_episode_dirs = false;
  double drain_timeout_s = 60;
  std::vector<std::string> server_hosts;
  bool verbose = false;
  BusFlags bus;
};

// The registered names a worker serves: all of them, or the listed ones, each checked.
std::vector<std::string> Served(const std::string& flag, const std::string& what, const std::vector<std::string>& listed,
                                const std::vector<std::string>& known) {
  for (const std::string& name : listed) {
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw std::invalid_argument(flag + ": unknown " + what + " '" + name + "' (known: " + JoinNames(known) + ")");
  }
  return listed.empty() ? known : listed;
}

void RunWorker(const WorkerFlags& f, const CLI::App& root) {
  RequireEpisodeUnlessEpisodeCmd(root, f.episode_cmd);
  StopSignals signals;
  SetupLogging(f.verbose);
  BusFlags bus_flags = f.bus;
  // --server-host adds the server to the discovery peers.
  bus_flags.peers.insert(bus_flags.peers.end(), f.server_hosts.begin(), f.server_hosts.end());

  worker::WorkerOptions o;
  o.bus = ResolveBus(bus_flags);
  o.worker_id = f.id;
  o.slots = f.slots;
  const api::Catalog catalog = sim::FarmCatalog();
  o.boards = Served("--boards", "board", f.boards, catalog.boards);
  o.clocks = Served("--clocks", "clock", f.clocks, catalog.clocks);
  // ROS methods wherever this host can fly them (the bridge built, ROS installed).
  if (const std::string why = sim::LinkUnavailableReason(sim::kRosMethod, "emulated"); why.empty()) {
    o.features.push_back("ros");
  } else {
    spdlog::info("not serving ROS methods: {}", why);
  }
  o.calibration_id = f.calibration_id;
  if (!f.episode_cmd.empty()) o.episode_command = worker::SplitCommand(f.episode_cmd);
  o.limits.wall_timeout = std::chrono::seconds(static_cast<std::int64_t>(f.episode_timeout_s));
  o.limits.memory_bytes = f.episode_memory_mb * 1024 * 1024;
  o.limits.cpu_seconds = f.episode_cpu_s > 0 ? f.episode_cpu_s
                                             : 4 * static_cast<std::int64_t>(f.episode_timeout_s);
  const auto state = worker::DefaultStateDir(o.bus);
  o.spool_dir = f.spool.empty() ? state / "spool" : std::filesystem::path(f.spool);
  o.work_dir = f.work_dir.empty() ? state / "work" : std::filesystem::path(f.work_dir);
  o.keep_episode_dirs = f.keep_episode_dirs;
  o.drain_timeout = std::chrono::seconds(static_cast<std::int64_t>(f.drain_timeout_s));

  worker::Worker w(o);
  // First SIGTERM/SIGINT: finish running episodes (up to --drain-timeout); second: abandon.
  signals.Watch([&w](int count) {
    spdlog::info("signal: {}", count == 1 ? "draining" : "abandoning running episodes");
    w.RequestStop(count > 1);
  });
  w.Run();
}

}  // namespace

void RegisterWorkerCommand(CLI::App& app) {
  auto f = std::make_shared<WorkerFlags>();
  CLI::App* sub = app.add_subcommand("worker", "Run a farm worker: episodes in child processes");
  sub->add_option("--slots", f->slots, "episodes run at once")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  sub->add_option("--id", f->id, "worker id (default: HOSTNAME-PID)");
  sub->add_option("--boards", f->boards, "boards served (comma-separated; default: all)")
      ->delimiter(',');
  sub->add_option("--clocks", f->clocks, "clocks served (comma-separated; default: all)")
      ->delimiter(',');
  sub->add_option("--calibration-id", f->calibration_id, "host calibration the episodes use");
  sub->add_option("--episode-cmd", f->episode_cmd,
                  "episode command; gets --spec-file F --result-file F (default: enavi episode)")
      ->envname("ENAVI_EPISODE_CMD");
  sub->add_option("--episode-timeout", f->episode_timeout_s, "wall-clock limit per episode, s")
      ->check(CLI::Range(1.0, 7 * 24 * 3600.0))
      ->capture_default_str();
  sub->add_option("--episode-memory-mb", f->episode_memory_mb,
                  "address-space limit per episode process, MiB (0: none)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 30))
      ->capture_default_str();
  sub->add_option("--episode-cpu", f->episode_cpu_s,
                  "CPU-time limit per episode process, s (default: 4 x --episode-timeout)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 30));
  sub->add_option("--spool", f->spool, "directory for unacknowledged results");
  sub->add_option("--work-dir", f->work_dir, "directory for per-episode files");
  sub->add_flag("--keep-episode-dirs", f->keep_episode_dirs, "keep spec, result and logs");
  sub->add_option("--drain-timeout", f->drain_timeout_s,
                  "on SIGTERM, seconds running episodes may finish")
      ->check(CLI::Range(0.0, 24 * 3600.0))
      ->capture_default_str();
  sub->add_option("--server-host", f->server_hosts,
                  "the server's host (adds it to --peers; comma-separated)")
      ->delimiter(',');
  sub->add_flag("-v,--verbose", f->verbose, "debug logging");
  AddBusFlags(sub, &f->bus);
  sub->callback([f, &app] { RunWorker(*f, app); });
}

}  // namespace enavi::cli
