#pragma once
// The metrics of a result record, generically: every number or boolean of the flat result JSON
// (api::ResultSummaryJson), nested objects flattened with dots ("eci.mean",
// "task_cpu_util_pct.perception"). Tables, `enavi compare` and the dashboard read metrics
// through this, so a field added to the result record shows up everywhere without a code change.

#include <map>
#include <string>

#include <nlohmann/json_fwd.hpp>

namespace enavi::api {

/// Numeric fields of a result record (booleans as 0/1). Identity fields (seed, attempt, ...) and
/// strings are left out.
std::map<std::string, double> ResultMetrics(const nlohmann::json& record);

}  // namespace enavi::api
