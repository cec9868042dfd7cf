#include "navstack/rl/shipped_policy.h"

#include <stdexcept>

namespace enavi::navstack::rl {

std::shared_ptr<const PolicyFile> LoadPolicyOrShipped(const std::string& path) {
  if (!path.empty()) return std::make_shared<const PolicyFile>(LoadFrequencyPolicy(path));
  static const std::shared_ptr<const PolicyFile> shipped = [] {
    const auto& files = ShippedPolicyFiles();
    const auto it = files.find(kShippedPolicyName);
    if (it == files.end()) return std::shared_ptr<const PolicyFile>();
    return std::make_shared<const PolicyFile>(
        PolicyFromJson(nlohmann::json::parse(it->second), std::string("shipped ") + kShippedPolicyName));
  }();
  if (!shipped)
    throw std::invalid_argument(std::string("policy: this build ships no trained E-Navi policy (") + kShippedPolicyName +
                                "); train one with `enavi train` and pass it with --policy FILE");
  return shipped;
}

}  // namespace enavi::navstack::rl
