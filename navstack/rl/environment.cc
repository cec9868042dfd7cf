#include "navstack/rl/environment.h"

#include <stdexcept>
#include <vector>

namespace enavi::navstack::rl {

Rollout CollectEpisode(Environment* env, const ActorCritic& net, std::uint64_t seed, ActMode mode,
                       int max_steps, std::int64_t policy_iteration) {
  if (env->obs_dim() != net.obs_dim() || env->num_actions() != net.num_actions()) {
    throw std::invalid_argument("CollectEpisode: environment and policy shapes differ");
  }
  Rng rng(DeriveSeed(seed, 0x5a3b1e));
  env->Reset(seed);
  ActorCritic::Workspace ws = net.MakeWorkspace();
  Eigen::VectorXd obs(net.obs_dim());
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(net.num_actions()));

  Rollout ro;
  ro.policy_iteration = policy_iteration;
  for (int t = 0; t < max_steps; ++t) {
    env->Observe(obs, mask);
    const PolicyOutput out = net.Act(obs, mask, mode, &rng, &ws);
    const Environment::StepResult step = env->Step(out.action);
    ro.steps.push_back({obs, out.action, mask, out.log_prob, out.value, step.reward, step.terminated});
    if (step.terminated) return ro;
  }
  // Time-out: not a terminal; bootstrap from the value of where we stopped.
  env->Observe(obs, mask);
  ro.bootstrap_value = net.Act(obs, mask, ActMode::kGreedy, nullptr, &ws, false, true).value;
  return ro;
}

}  // namespace enavi::navstack::rl
