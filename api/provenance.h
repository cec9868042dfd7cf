#pragma once
// Where a job or a result came from: the enavi build (version and git commit, written by
// cmake/BuildInfo.cmake at configure time) and content digests of the inputs that change
// results (policy file, cost-model coefficients). Stored with every job and result so a
// regression can be traced to the change that caused it.

#include <string>

#include "api/content_hash.h"  // Sha256Hex, Sha256File: the digests provenance records

namespace enavi::api {

/// The project version this binary was built as ("0.1.0").
std::string BuildVersion();
/// The git commit it was built from (12 hex digits, "-dirty" when the tree had local changes),
/// or "unknown" when built outside a git checkout.
std::string BuildCommit();

/// A result's provenance is its notes under this prefix (workers/sim/episode_provenance.h writes
/// them, `enavi compare` reads them).
inline constexpr const char* kProvenanceNotePrefix = "provenance.";

}  // namespace enavi::api
