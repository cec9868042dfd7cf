#pragma once
// The metrics of a result record, generically: every number or boolean of the flat result JSON
// (api::ResultSummaryJson), nested objects flattened with dots ("eci.mean",
// "task_cpu_util_pct.perception"). Tables, `enavi compare` and the dashboard read metrics
// through this, so a field added to the result record shows up everywhere without a code change.
// The store refuses a record whose numbers are not finite (ResultError) before any of them reads it.

#include <map>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "api/episode.h"

namespace enavi::api {

/// Numeric fields of a result record (booleans as 0/1). Identity fields (seed, attempt, ...) and
/// strings are left out.
std::map<std::string, double> ResultMetrics(const nlohmann::json& record);

/// True for a metric of a count map whose keys are only the ones that occurred
/// ("replans_by_trigger.difference"): where a record lacks it, the count is 0, not unknown.
bool AbsentMeansZero(const std::string& metric);

/// Why `r` cannot be stored as the result of the episode `expected`, or "" when it can: "FIELD:
/// REASON" for a spec of another episode (world, seed, board, method or clock differs), a metric
/// or series sample that is not finite, or a series column whose length is neither 0 nor t's.
std::string ResultError(const EpisodeResult& r, const EpisodeSpec& expected);

}  // namespace enavi::api
