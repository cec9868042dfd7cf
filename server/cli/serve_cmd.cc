// enavi serve: the farm server daemon (scheduler + SQLite store + HTTP API).
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>

#include <spdlog/spdlog.h>

#include "api/atomic_file.h"
#include "server/cli/commands.h"
#include "server/cli/farm_flags.h"
#include "server/http/http_api.h"
#include "server/scheduler/farm_server.h"
#include "server/store/store.h"
#include "workers/sim/episode_config.h"

namespace enavi::cli {
namespace {

struct ServeFlags {
  std::string db = "enavi-farm.db";
  std::string http = "127.0.0.1:" + std::to_string(api::kDefaultHttpPort);
  std::string token;
  std::vector<std::string> world_roots;
  int max_attempts = 3;
  double lease_s = 15;
  server::HttpOptions limits;                 // the HTTP limits' defaults
  server::FarmServerOptions result_limits;    // the result and rollout size limits' defaults
  std::string ready_file;
  std::vector<std::string> unchecked_override_prefixes;
  bool verbose = false;
  BusFlags bus;
};


void RunServe(const ServeFlags& f) {
  StopSignals signals;
  SetupLogging(f.verbose);
  const auto [host, port] = ParseHostPort(f.http, "--http");

  server::StoreOptions store_options;
  store_options.max_attempts = f.max_attempts;
  server::Store store(f.db, store_options);

  server::FarmServerOptions options;
  options.bus = ResolveBus(f.bus);
  options.lease = std::chrono::milliseconds(static_cast<std::int64_t>(f.lease_s * 1000));
  options.max_result_bytes = f.result_limits.max_result_bytes;
  options.max_rollout_bytes = f.result_limits.max_rollout_bytes;
  server::FarmServer farm(&store, options);

  server::HttpOptions http = f.limits;
  http.host = host;
  http.port = port;
  http.token = f.token;
  for (const auto& r : f.world_roots) http.job_spec.allowed_roots.emplace_back(r);
  http.job_spec.catalog = sim::FarmCatalog();
  http.job_spec.catalog.unchecked_prefixes = f.unchecked_override_prefixes;
  server::HttpApi api(&farm, http);

  // The port first: a server that cannot listen (another on the address) exits before its farm
  // touches the database's leases or the workers' bus.
  api.Start();
  farm.Start();
  spdlog::info("enavi serve: {} (db {}, DDS domain {}, partition {}, pid {})", api.url(), f.db,
               options.bus.domain_id, options.bus.partition, getpid());
  // Written once serving, atomically, so a script or test can wait for it and read the URL.
  if (!f.ready_file.empty()) api::WriteFileAtomic(f.ready_file, api.url() + "\n");

  const int sig = signals.Wait();
  spdlog::info("enavi serve: signal {}, stopping", sig);
  api.Stop();
  farm.Stop();
}

}  // namespace

void RegisterServeCommand(CLI::App& app) {
  auto f = std::make_shared<ServeFlags>();
  CLI::App* sub = app.add_subcommand("serve", "Run the farm server: scheduler, SQLite store, HTTP API");
  sub->add_option("--db", f->db, "SQLite database; created if missing, resumed if not")
      ->capture_default_str();
  sub->add_option("--http", f->http, "HTTP API address HOST:PORT (port 0: any free port)")
      ->capture_default_str();
  sub->add_option("--token", f->token,
                  "token required on state-changing requests; needed when --http is not loopback")
      ->envname("ENAVI_TOKEN");
  sub->add_option("--world-root", f->world_roots,
                  "allowed root for world and policy files in job specs (repeatable; default: cwd)");
  sub->add_option("--max-attempts", f->max_attempts, "attempts per episode before it fails")
      ->check(CLI::Range(1, 10))
      ->capture_default_str();
  sub->add_option("--lease", f->lease_s, "lease length in seconds (renewed by worker heartbeats)")
      ->check(CLI::Range(2.0, 3600.0))
      ->capture_default_str();
  // Limits that protect the server (docs/farm.md, "Limits").
  sub->add_option("--max-body-bytes", f->limits.max_body_bytes,
                  "largest HTTP request body (job specs); larger: HTTP 413")
      ->check(CLI::Range(std::size_t{1} << 10, std::size_t{1} << 30))
      ->capture_default_str();
  sub->add_option("--max-policy-bytes", f->limits.max_policy_bytes,
                  "largest policy upload (POST /api/policies); larger: HTTP 413")
      ->check(CLI::Range(std::size_t{1} << 10, std::size_t{1} << 30))
      ->capture_default_str();
  sub->add_option("--max-job-episodes", f->limits.max_job_episodes,
                  "most episodes one job may have; more: HTTP 413")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000000}))
      ->capture_default_str();
  sub->add_option("--max-jobs-per-minute", f->limits.max_jobs_per_minute,
                  "job submissions per client address and minute (0: no limit); more: HTTP 429")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  sub->add_option("--max-result-bytes", f->result_limits.max_result_bytes,
                  "largest episode result from a worker (series, events, error); larger: refused, "
                  "logged, the attempt fails")
      ->check(CLI::Range(std::size_t{1} << 10, std::size_t{1} << 30))
      ->capture_default_str();
  sub->add_option("--max-rollout-bytes", f->result_limits.max_rollout_bytes,
                  "largest rollout from a worker (at most the bus's one-sample limit); larger: "
                  "refused, logged, the attempt fails")
      ->check(CLI::Range(std::size_t{1} << 10, api::kMaxRolloutBytes))
      ->capture_default_str();
  sub->add_option("--ready-file", f->ready_file, "write the HTTP URL here once serving");
  sub->add_option("--unchecked-overrides", f->unchecked_override_prefixes,
                  "override-name prefix that passes unchecked at submit, for workers whose --episode-cmd "
                  "is not `enavi fly` (repeatable)")
      ->group("");
  sub->add_flag("-v,--verbose", f->verbose, "debug logging");
  AddBusFlags(sub, &f->bus);
  sub->callback([f] { RunServe(*f); });
}

}  // namespace enavi::cli
