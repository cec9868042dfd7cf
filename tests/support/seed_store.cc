#include "tests/support/seed_store.h"

#include "api/job_spec.h"
#include "api/provenance.h"
#include "server/store/ingest.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/worker_store.h"
#include "tests/support/synthetic_result.h"
#include "workers/sim/episode_config.h"

namespace enavi::testing {

std::string SubmitJob(server::Store& store, const std::string& spec_yaml, std::int64_t now_ms) {
  // Validated against the registry's methods, as `enavi serve` does; fake.* knobs pass.
  api::JobSpecOptions options;
  options.catalog = sim::FarmCatalog();
  options.catalog.unchecked_prefixes = {"fake."};
  const api::JobSpec job = api::ParseJobSpec(spec_yaml, "seed.yaml", options);
  server::JobMeta meta;
  meta.labels = job.labels;
  meta.provenance = {{"enavi_version", api::BuildVersion()}, {"git_commit", api::BuildCommit()},
                     {"clock", job.clock}, {"cost", job.cost}};
  return store.jobs().CreateJob(job.name, spec_yaml, api::ExpandJob(job), now_ms, meta);
}

std::string SeedJob(server::Store& store, const std::string& spec_yaml, std::int64_t now_ms,
                    const std::string& worker, int series_len) {
  const std::string id = SubmitJob(store, spec_yaml, now_ms);
  api::WorkerStatus status;
  status.worker_id = worker;
  status.host = worker.substr(0, worker.rfind('-'));
  status.slots = 4;
  status.version = api::BuildVersion();
  status.calibration_id = "reference";
  store.workers().RecordWorker(status, now_ms);
  server::WorkerCapabilities caps;  // any board and clock
  caps.features = {"ros"};
  // Lease and answer in batches, as a farm would.
  while (true) {
    const auto leases = store.leases().LeaseEpisodes(worker, 500, caps, now_ms + 60000, now_ms);
    if (leases.empty()) break;
    std::vector<api::ResultMessage> batch;
    for (const auto& l : leases) {
      api::ResultMessage m;
      m.episode_id = l.episode_id;
      m.attempt = l.attempt;
      m.worker_id = worker;
      m.job_id = l.job_id;
      m.wall_time_s = 1.0;
      if (l.spec.overrides.count("fake.exit_code")) {
        m.status = api::ResultStatus::kError;
        m.error = "episode exited with code " + std::to_string(static_cast<int>(l.spec.overrides.at("fake.exit_code")));
      } else {
        m.result = SyntheticResult(l.spec, series_len);
      }
      batch.push_back(std::move(m));
    }
    store.ingest().Ingest(batch, ++now_ms);
  }
  return id;
}

}  // namespace enavi::testing
