#pragma once
// Internal: a network's weights as one JSON block of packed little-endian floats in base64 with
// their sha256, the "parameters" of every policy file (policy_io.h, nav_policy.h).

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "navstack/rl/json_read.h"

namespace enavi::navstack::rl {

/// Width of the packed weights.
enum class WeightPrecision { kFloat32, kFloat64 };

namespace detail {

/// Spells weight i's field name (called only when an error names it).
using WeightName = std::function<std::string(std::size_t)>;

/// {"dtype", "byte_order", "encoding", "layout", "count", "sha256", "data"}.
/// @throws std::domain_error naming the weight when one is not finite at `precision`.
nlohmann::json EncodeWeights(const std::vector<double>& values, WeightPrecision precision, const std::string& layout,
                             const WeightName& name_of);
/// The `count` weights of block `j` (at `field`), checked against `layout`, its length and its
/// sha256. @throws std::invalid_argument through `r` naming the field.
std::vector<double> DecodeWeights(const nlohmann::json& j, const JsonReader& r, const std::string& field,
                                  std::size_t count, const std::string& layout, const WeightName& name_of);

}  // namespace detail
}  // namespace enavi::navstack::rl
