#pragma once
// Which way is better for each result metric, and how large a change must be before
// `enavi compare` calls it a regression. One line per metric: a metric the result record gains
// is judged once it has a line here; until then it is still shown, without a verdict.

#include <filesystem>
#include <map>
#include <string>

namespace enavi::server {

enum class Direction { kLower, kHigher, kNone };  ///< which way is better; kNone: shown only

/// The values a metric takes, for the dashboard's axes: kOutcome is 0 or 1 per flight (a cell's
/// mean is a rate, drawn on 0..1), kNonNegative never goes below 0 (counts, times, lengths,
/// ratios, a std), kAny is unbounded (a metric without a default rule).
enum class MetricRange { kAny, kNonNegative, kOutcome };

/// A change is beyond the threshold when |delta| > max(abs, rel x |base mean|).
struct MetricRule {
  Direction direction = Direction::kNone;
  double abs = 0.0;
  double rel = 0.0;
  /// Averaged over pairs where both flights succeeded (a crash's flight time is not a flight
  /// time), as the paper-style table does.
  bool success_only = false;
  MetricRange range = MetricRange::kAny;
};

using MetricRules = std::map<std::string, MetricRule>;

/// The defaults (metric name -> rule).
const MetricRules& DefaultMetricRules();

/// The defaults with a YAML file's changes applied:
///   metrics:
///     flight_time_s: {rel: 0.10}              # change any of direction, abs, rel, success_only
///     my_metric: {direction: higher, abs: 1}  # a metric without a default rule
/// @throws std::invalid_argument "FILE:LINE: field: reason" on bad input.
MetricRules LoadMetricRules(const std::filesystem::path& path);
MetricRules ParseMetricRules(const std::string& yaml_text, const std::string& file_name);

const char* DirectionName(Direction d);
const char* RangeName(MetricRange r);  ///< "any", "non_negative", "outcome"

}  // namespace enavi::server
