#include "navstack/rl/json_read.h"

namespace enavi::navstack::rl::detail {

Eigen::VectorXd JsonReader::Vector(const nlohmann::json& j, const std::string& field, Eigen::Index expected) const {
  const std::vector<double> v = Numbers(j, field, static_cast<long>(expected));
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

nlohmann::json ToJson(const Eigen::Ref<const Eigen::VectorXd>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

}  // namespace enavi::navstack::rl::detail
