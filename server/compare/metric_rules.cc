#include "server/compare/metric_rules.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace enavi::server {

const MetricRules& DefaultMetricRules() {
  // Thresholds: outcome counts (success, collisions, stops) regress on any drop; continuous
  // metrics on a change of a few percent, above what a one-grid-cell (0.1 m) path difference or a
  // re-ordered job in the executor moves them.
  static const MetricRules rules = {
      {"success", {Direction::kHigher, 0.0, 0.0, false}},
      {"collided", {Direction::kLower, 0.0, 0.0, false}},
      {"timed_out", {Direction::kLower, 0.0, 0.0, false}},
      {"flight_time_s", {Direction::kLower, 0.0, 0.05, true}},
      {"path_length_m", {Direction::kLower, 0.0, 0.05, true}},
      {"velocity_std_mps", {Direction::kLower, 0.0, 0.10, false}},
      {"accel_peak_mps2", {Direction::kLower, 0.0, 0.10, false}},
      {"nav_cpu_util_pct", {Direction::kLower, 1.0, 0.05, false}},
      {"deadline_miss_ratio", {Direction::kLower, 0.01, 0.10, false}},
      {"deadline_misses", {Direction::kLower, 1.0, 0.10, false}},
      {"replans", {Direction::kLower, 1.0, 0.20, false}},
      {"emergency_stops", {Direction::kLower, 0.0, 0.0, false}},
      {"plan_failures", {Direction::kLower, 0.0, 0.0, false}},
      {"time_stopped_s", {Direction::kLower, 0.1, 0.10, false}},
      {"setpoint_lag_p95_m", {Direction::kLower, 0.0, 0.10, false}},
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

namespace {

[[noreturn]] void Fail(const std::string& file, const YAML::Node& at, const std::string& field,
                       const std::string& reason) {
  throw std::invalid_argument(file + ":" + std::to_string(at.Mark().line + 1) + ": " + field +
                              ": " + reason);
}

double NonNegative(const std::string& file, const YAML::Node& n, const std::string& field) {
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    Fail(file, n, field, "expected a number, got '" + n.Scalar() + "'");
  }
  if (!std::isfinite(v) || v < 0) Fail(file, n, field, "expected a finite number >= 0");
  return v;
}

}  // namespace

MetricRules ParseMetricRules(const std::string& yaml_text, const std::string& file) {
  YAML::Node loaded;
  try {
    loaded = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(file + ":" + std::to_string(e.mark.line + 1) + ": yaml: " + e.msg);
  }
  const YAML::Node root = loaded;
  MetricRules rules = DefaultMetricRules();
  if (root.IsNull()) return rules;
  if (!root.IsMap()) Fail(file, root, "thresholds", "expected a map with metrics:");
  for (const auto& kv : root) {
    if (kv.first.Scalar() != "metrics") Fail(file, kv.first, kv.first.Scalar(), "unknown key (allowed: metrics)");
  }
  const YAML::Node metrics = root["metrics"];
  if (!metrics) return rules;
  if (!metrics.IsMap()) Fail(file, metrics, "metrics", "expected a map of metric: {direction, abs, rel}");
  std::set<std::string> seen;
  for (const auto& kv : metrics) {
    const std::string name = kv.first.Scalar();
    const std::string field = "metrics." + name;
    if (!seen.insert(name).second) Fail(file, kv.first, field, "duplicate metric");
    if (!kv.second.IsMap()) Fail(file, kv.second, field, "expected a map of direction, abs, rel, success_only");
    MetricRule rule = rules.count(name) ? rules.at(name) : MetricRule{};
    for (const auto& setting : kv.second) {
      const std::string key = setting.first.Scalar();
      if (key == "direction") {
        const std::string d = setting.second.Scalar();
        if (d == "lower") rule.direction = Direction::kLower;
        else if (d == "higher") rule.direction = Direction::kHigher;
        else if (d == "none") rule.direction = Direction::kNone;
        else Fail(file, setting.second, field + ".direction", "'" + d + "': expected lower, higher or none");
      } else if (key == "abs") {
        rule.abs = NonNegative(file, setting.second, field + ".abs");
      } else if (key == "rel") {
        rule.rel = NonNegative(file, setting.second, field + ".rel");
      } else if (key == "success_only") {
        const std::string b = setting.second.Scalar();
        if (b != "true" && b != "false") Fail(file, setting.second, field + ".success_only", "expected true or false");
        rule.success_only = b == "true";
      } else {
        Fail(file, setting.first, field + "." + key, "unknown key (allowed: direction, abs, rel, success_only)");
      }
    }
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
