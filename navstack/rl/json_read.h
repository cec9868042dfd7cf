#pragma once
// Internal: the validated JSON reader of api/json_read.h with the Eigen reads and writes the
// policy, checkpoint and rollout files need. Not part of the public API.

#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "api/json_read.h"

namespace enavi::navstack::rl::detail {

using api::ParseJson;
using api::ReadJsonFile;

class JsonReader : public api::JsonReader {
 public:
  using api::JsonReader::JsonReader;
  /// Array of finite numbers; expected < 0 accepts any length.
  Eigen::VectorXd Vector(const nlohmann::json& j, const std::string& field, Eigen::Index expected = -1) const;
};

/// Vector as a JSON array (doubles are written in shortest round-trip form).
nlohmann::json ToJson(const Eigen::Ref<const Eigen::VectorXd>& v);

}  // namespace enavi::navstack::rl::detail
