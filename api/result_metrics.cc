#include "api/result_metrics.h"

#include <array>
#include <cmath>

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

}  // namespace

std::map<std::string, double> ResultMetrics(const nlohmann::json& record) {
  std::map<std::string, double> out;
  if (!record.is_object()) return out;
  nlohmann::json copy = record;
  for (const char* k : kIdentity) copy.erase(k);
  Flatten(copy, "", &out);
  return out;
}

}  // namespace enavi::api
