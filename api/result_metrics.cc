#include "api/result_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>

namespace enavi::api {
namespace {

// Fields that identify an episode or where it ran, not how it flew.
constexpr std::array<const char*, 6> kIdentity = {"seed", "attempt", "wall_time_s", "spec",
                                                  "events", "series"};

void Flatten(const nlohmann::json& j, const std::string& prefix, std::map<std::string, double>* out) {
  for (const auto& [key, value] : j.items()) {
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (value.is_boolean()) {
      (*out)[name] = value.get<bool>() ? 1.0 : 0.0;
    } else if (value.is_number()) {
      const double v = value.get<double>();
      if (std::isfinite(v)) (*out)[name] = v;
    } else if (value.is_object() && key != "notes") {
      Flatten(value, name, out);
    }
  }
}

// The first non-finite number under `j`, as its field path ("" when all are finite).
std::string NonFiniteField(const nlohmann::json& j, const std::string& path) {
  if (j.is_number_float()) return std::isfinite(j.get<double>()) ? "" : path;
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      if (std::string f = NonFiniteField(value, path.empty() ? key : path + "." + key); !f.empty()) return f;
    }
  }
  if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      if (std::string f = NonFiniteField(j[i], path + "[" + std::to_string(i) + "]"); !f.empty()) return f;
    }
  }
  return "";
}

}  // namespace

std::map<std::string, double> ResultMetrics(const nlohmann::json& record) {
  std::map<std::string, double> out;
  if (!record.is_object()) return out;
  nlohmann::json copy = record;
  for (const char* k : kIdentity) copy.erase(k);
  Flatten(copy, "", &out);
  return out;
}

bool AbsentMeansZero(const std::string& metric) { return metric.rfind("replans_by_trigger.", 0) == 0; }

std::string ResultError(const EpisodeResult& r, const EpisodeSpec& expected) {
  // The identity of the episode: the worker echoes the spec it was given (a collection episode's
  // policy becomes its hash, so the policy is not compared).
  const std::pair<const char*, bool> same[] = {
      {"world", r.spec.world == expected.world},   {"seed", r.spec.seed == expected.seed},
      {"board", r.spec.board == expected.board},   {"method", r.spec.method == expected.method},
      {"clock", r.spec.clock == expected.clock}};
  for (const auto& [field, ok] : same) {
    if (!ok) return std::string("spec.") + field + ": not this episode's";
  }
  if (const std::string f = NonFiniteField(ResultSummaryJson(r), ""); !f.empty()) return f + ": not a finite number";
  const TimeSeries& s = r.series;
  const std::pair<const char*, std::size_t> columns[] = {
      {"position", s.position.size()}, {"velocity", s.velocity.size()}, {"eci", s.eci.size()},
      {"f_per", s.f_per.size()},       {"f_col", s.f_col.size()},       {"f_dif", s.f_dif.size()},
      {"res", s.res.size()},           {"utilisation", s.utilisation.size()}, {"events", s.events.size()},
      {"wind_speed", s.wind_speed.size()}, {"odometry_error", s.odometry_error.size()}};
  for (const auto& [column, n] : columns) {
    if (n != 0 && n != s.t.size()) {
      return std::string("series.") + column + ": " + std::to_string(n) + " samples, t has " +
             std::to_string(s.t.size());
    }
  }
  const std::pair<const char*, const std::vector<double>*> numbers[] = {
      {"t", &s.t},         {"eci", &s.eci}, {"f_per", &s.f_per}, {"f_col", &s.f_col},
      {"f_dif", &s.f_dif}, {"res", &s.res}, {"utilisation", &s.utilisation},
      {"wind_speed", &s.wind_speed}, {"odometry_error", &s.odometry_error}};
  const auto finite = [](double v) { return std::isfinite(v); };
  for (const auto& [column, values] : numbers) {
    if (!std::all_of(values->begin(), values->end(), finite)) return std::string("series.") + column + ": not a finite number";
  }
  const std::pair<const char*, const std::vector<Vec3>*> vectors[] = {{"position", &s.position}, {"velocity", &s.velocity}};
  for (const auto& [column, values] : vectors) {
    for (const Vec3& v : *values) {
      if (!std::all_of(v.begin(), v.end(), finite)) return std::string("series.") + column + ": not a finite number";
    }
  }
  return "";
}

}  // namespace enavi::api
