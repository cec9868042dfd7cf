#include "server/compare/metric_rules.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "api/yaml_read.h"

namespace enavi::server {

const MetricRules& DefaultMetricRules() {
  // Thresholds: outcome counts (success, collisions, stops) regress on any drop; continuous
  // metrics on a change of a few percent, above what a one-grid-cell (0.1 m) path difference or a
  // re-ordered job in the executor moves them. Every default metric is an outcome (0/1) or a
  // quantity that cannot be negative.
  constexpr MetricRange kOut = MetricRange::kOutcome, kNonNeg = MetricRange::kNonNegative;
  static const MetricRules rules = {
      {"success", {Direction::kHigher, 0.0, 0.0, false, kOut}},
      {"collided", {Direction::kLower, 0.0, 0.0, false, kOut}},
      {"timed_out", {Direction::kLower, 0.0, 0.0, false, kOut}},
      {"flight_time_s", {Direction::kLower, 0.0, 0.05, true, kNonNeg}},
      {"path_length_m", {Direction::kLower, 0.0, 0.05, true, kNonNeg}},
      {"velocity_std_mps", {Direction::kLower, 0.0, 0.10, false, kNonNeg}},
      {"accel_peak_mps2", {Direction::kLower, 0.0, 0.10, false, kNonNeg}},
      {"nav_cpu_util_pct", {Direction::kLower, 1.0, 0.05, false, kNonNeg}},
      {"deadline_miss_ratio", {Direction::kLower, 0.01, 0.10, false, kNonNeg}},
      {"deadline_misses", {Direction::kLower, 1.0, 0.10, false, kNonNeg}},
      {"replans", {Direction::kLower, 1.0, 0.20, false, kNonNeg}},
      {"emergency_stops", {Direction::kLower, 0.0, 0.0, false, kNonNeg}},
      {"plan_failures", {Direction::kLower, 0.0, 0.0, false, kNonNeg}},
      {"time_stopped_s", {Direction::kLower, 0.1, 0.10, false, kNonNeg}},
      {"setpoint_lag_p95_m", {Direction::kLower, 0.0, 0.10, false, kNonNeg}},
  };
  return rules;
}

const char* DirectionName(Direction d) {
  switch (d) {
    case Direction::kLower: return "lower";
    case Direction::kHigher: return "higher";
    case Direction::kNone: return "none";
  }
  return "none";
}

const char* RangeName(MetricRange r) {
  switch (r) {
    case MetricRange::kAny: return "any";
    case MetricRange::kNonNegative: return "non_negative";
    case MetricRange::kOutcome: return "outcome";
  }
  return "any";
}

MetricRules ParseMetricRules(const std::string& yaml_text, const std::string& file) {
  const api::YamlReader reader(file);
  const YAML::Node root = reader.Load(yaml_text);  // const: operator[] would insert what it looks up
  MetricRules rules = DefaultMetricRules();
  if (root.IsNull()) return rules;
  if (!root.IsMap()) reader.Fail(root, "thresholds", "expected a map with metrics:");
  reader.CheckKeys(root, "", {"metrics"});
  const YAML::Node metrics = root["metrics"];
  if (!metrics) return rules;
  const api::YamlReader::Map by_name(reader, metrics, "metrics", {});
  for (const auto& kv : metrics) {
    const std::string name = kv.first.Scalar();
    const api::YamlReader::Map m(reader, kv.second, by_name.Field(name), {"direction", "abs", "rel", "success_only"});
    MetricRule rule = rules.count(name) ? rules.at(name) : MetricRule{};
    if (m.Has("direction")) {
      const std::string d = reader.Scalar(m.Get("direction"), m.Field("direction"));
      if (d == "lower") rule.direction = Direction::kLower;
      else if (d == "higher") rule.direction = Direction::kHigher;
      else if (d == "none") rule.direction = Direction::kNone;
      else reader.Fail(m.Get("direction"), m.Field("direction"), "'" + api::YamlReader::Shown(d) + "': expected lower, higher or none");
    }
    constexpr double kInf = std::numeric_limits<double>::infinity();
    if (m.Has("abs")) rule.abs = reader.Range(m.Get("abs"), m.Field("abs"), 0.0, kInf);
    if (m.Has("rel")) rule.rel = reader.Range(m.Get("rel"), m.Field("rel"), 0.0, kInf);
    if (m.Has("success_only")) rule.success_only = reader.Bool(m.Get("success_only"), m.Field("success_only"));
    rules[name] = rule;
  }
  return rules;
}

MetricRules LoadMetricRules(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path.string() + ":1: file: cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseMetricRules(text.str(), path.string());
}

}  // namespace enavi::server
