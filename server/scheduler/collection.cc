#include "server/scheduler/collection.h"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "api/content_hash.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/policy_io.h"
#include "server/scheduler/farm_server.h"
#include "server/store/collect_store.h"

namespace enavi::server {

std::string StorePolicy(Store* store, const std::string& text, const std::string& source) {
  const std::string canonical =
      navstack::rl::IsNavPolicyText(text)
          ? navstack::rl::CanonicalNavPolicyText(text, source)
          : navstack::rl::CanonicalPolicyText(navstack::rl::FrequencyPolicyFromText(text, source));
  const std::string hash = api::Sha256Hex(canonical);
  store->collect().PutPolicy(hash, canonical, NowMs());
  return hash;
}

std::optional<CollectionInfo> PrepareCollection(Store* store, const api::JobSpec& job,
                                                std::vector<api::EpisodeSpec>* episodes) {
  const std::string prefix = api::kPolicyHashPrefix;
  if (!job.collect) {
    std::set<std::string> checked;
    for (const auto& e : *episodes) {
      if (api::IsPolicyHashRef(e.policy)) {
        throw std::invalid_argument("policy: " + e.policy +
                                    ": a policy by hash is for collection jobs (collect: rollouts)");
      }
      // Loaded once here, or a bad file fails every episode that flies it, each after its retries:
      // a nav policy (the learned method's) or a frequency policy, by its format.
      if (!e.policy.empty() && checked.insert(e.policy).second) {
        if (navstack::rl::IsNavPolicyFile(e.policy)) navstack::rl::LoadNavPolicy(e.policy);
        else navstack::rl::LoadFrequencyPolicy(e.policy);
      }
    }
    return std::nullopt;
  }
  for (const auto& e : *episodes) {
    if (e.policy != job.policy) {
      throw std::invalid_argument("episode_overrides.policy: a collection job flies one policy");
    }
  }
  std::string hash;
  if (api::IsPolicyHashRef(job.policy)) {
    hash = job.policy.substr(prefix.size());
    if (!store->collect().Policy(hash)) {
      throw std::invalid_argument("policy: " + job.policy + ": not on this server (POST /api/policies first)");
    }
  } else {
    std::ifstream in(job.policy, std::ios::binary);
    if (!in) throw std::invalid_argument("policy: cannot read '" + job.policy + "'");
    std::ostringstream text;
    text << in.rdbuf();
    hash = StorePolicy(store, text.str(), "policy file '" + job.policy + "'");
  }
  // The policy fits the method: a nav policy flies `learned`, a frequency policy `enavi`.
  const std::string stored = *store->collect().Policy(hash);
  const bool nav = navstack::rl::IsNavPolicyText(stored);
  const std::string& method = job.methods.front();
  if (nav != (method == "learned")) {
    throw std::invalid_argument("policy: " + job.policy + " is a " +
                                (nav ? "nav policy (method learned)" : "frequency policy (method enavi)") +
                                "; the job flies " + method);
  }
  if (nav && job.collect->sample &&
      !navstack::rl::NavPolicyFromJson(nlohmann::json::parse(stored), "policy " + job.policy).log_std()) {
    throw std::invalid_argument("sample: true draws from the nav policy's Gaussian, and policy " + job.policy +
                                " has no log_std (examples/torch_nav_ppo.py writes it); sample: false collects its "
                                "greedy actions");
  }
  for (auto& e : *episodes) e.policy = prefix + hash;
  return CollectionInfo{hash, job.collect->sample};
}

}  // namespace enavi::server
