#pragma once
// Fills a farm database with a finished job without running a farm: the job spec is parsed and
// expanded as `enavi submit` does, every episode is leased and answered with its synthetic
// result (synthetic_result.h) through ResultIngest::Ingest, as the scheduler would. An episode whose
// spec has the override `fake.exit_code` gets an error instead (failed with max_attempts 1).

#include <cstdint>
#include <string>

#include "server/store/store.h"

namespace enavi::testing {

/// Submits the job as `enavi submit` does and leaves its episodes pending; returns its id.
std::string SubmitJob(server::Store& store, const std::string& spec_yaml, std::int64_t now_ms);

/// Returns the job id. `worker` is recorded as the worker that ran every episode (ROS methods'
/// too: it offers every feature).
std::string SeedJob(server::Store& store, const std::string& spec_yaml, std::int64_t now_ms,
                    const std::string& worker = "seed-host-1", int series_len = 50);

}  // namespace enavi::testing
