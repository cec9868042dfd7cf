#pragma once
// Where `enavi compare` and GET /api/compare read a job from: a farm database or a farm server.
// Either way the job comes with its episodes' specs and its record (labels, the server build),
// so the report can say how two jobs differ before it compares their metrics.

#include <string>

#include "api/client.h"
#include "server/compare/compare.h"
#include "server/store/store.h"

namespace enavi::server {

/// The job `job_id` of `store`, named `name` in the report.
/// @throws std::invalid_argument when the store has no such job.
CompareInput CompareInputFromStore(Store& store, const std::string& job_id, const std::string& name);

/// The same through a farm server's HTTP API (a server without episode specs in its episode list
/// gives none: the report then says the specs were not compared).
CompareInput CompareInputFromServer(api::FarmClient& client, const std::string& job_id, const std::string& name);

}  // namespace enavi::server
