#pragma once
// Collection jobs at submission: the job's policy is validated, stored by content hash and named
// by that hash in every episode, so each episode records exactly which network it flew.

#include <optional>
#include <string>
#include <vector>

#include "api/job_spec.h"
#include "server/store/jobs.h"
#include "server/store/store.h"

namespace enavi::server {

/// Validates a policy (JSON text: a frequency policy, or a nav policy by its "format"), stores its
/// canonical bytes and returns their SHA-256.
/// @throws std::invalid_argument naming `source` for a policy that does not load.
std::string StorePolicy(Store* store, const std::string& text, const std::string& source);

/// For a collection job: stores its policy (a file, or a hash already stored), checks that it fits
/// the method (and has a log_std when a nav policy is sampled), points every
/// episode at "sha256:HASH" and returns what the store records. Nullopt for other jobs.
/// Any other job's policy files are loaded once, so a bad one is refused at submit.
/// @throws std::invalid_argument for an unknown policy hash, a bad policy file, or a policy hash
///   in a job that does not collect (only collection jobs fly policies by hash).
std::optional<CollectionInfo> PrepareCollection(Store* store, const api::JobSpec& job,
                                                std::vector<api::EpisodeSpec>* episodes);

}  // namespace enavi::server
