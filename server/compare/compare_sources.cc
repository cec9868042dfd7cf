#include "server/compare/compare_sources.h"

#include <stdexcept>

#include "server/store/jobs.h"
#include "server/store/queries.h"

namespace enavi::server {
namespace {

void SetJob(const api::JobProgress& p, CompareInput* in) {
  in->job_known = true;
  in->job_name = p.name;
  in->labels = p.labels;
  in->provenance = p.provenance;
}

}  // namespace

CompareInput CompareInputFromStore(Store& store, const std::string& job_id, const std::string& name) {
  const auto progress = store.jobs().Progress(job_id, 0);
  if (!progress) throw std::invalid_argument(name + ": no job '" + job_id + "'");
  CompareInput in;
  in.name = name;
  SetJob(*progress, &in);
  in.results = store.queries().Results(job_id);
  for (const EpisodeInfo& e : store.jobs().Episodes(job_id)) in.specs[e.id] = e.spec;
  return in;
}

CompareInput CompareInputFromServer(api::FarmClient& client, const std::string& job_id, const std::string& name) {
  CompareInput in;
  in.name = name;
  SetJob(client.Status(job_id), &in);
  in.results = client.Results(job_id);
  for (const auto& e : client.Episodes(job_id)) {
    if (e.contains("spec") && e.contains("id")) in.specs[e["id"].get<std::string>()] = e["spec"];
  }
  return in;
}

}  // namespace enavi::server
