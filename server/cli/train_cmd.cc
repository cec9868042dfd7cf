// `enavi train`: PPO training of E-Navi's frequency adapter from farm rollouts.
#include <unistd.h>

#include <cstdio>
#include <map>
#include <memory>

#include <spdlog/spdlog.h>

#include "server/cli/commands.h"
#include "server/train/trainer.h"
#include "workers/sim/episode_config.h"

namespace enavi::cli {

void RegisterTrainCommand(CLI::App& app) {
  auto o = std::make_shared<train::TrainOptions>();
  auto out = std::make_shared<std::string>("policy.json");
  auto work = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "train", "Train E-Navi's frequency adapter with PPO from rollouts collected on the farm");
  cmd->add_option("--boards", o->boards, "boards to train on")->delimiter(',')->capture_default_str();
  cmd->add_option("--scenarios", o->scenarios, "scenarios to train in")->delimiter(',')->capture_default_str();
  cmd->add_option("--iterations", o->iterations, "PPO iterations")->capture_default_str();
  cmd->add_option("--episodes-per-iter", o->episodes_per_iteration, "episodes flown per iteration")
      ->capture_default_str();
  cmd->add_option("--server", o->server,
                  "farm server URL (each iteration is a collection job there); default: a private local farm")
      ->envname("ENAVI_SERVER");
  cmd->add_option("--token", o->token, "the farm's token")->envname("ENAVI_TOKEN");
  cmd->add_option("--workers", o->workers, "private local farm: worker processes")->capture_default_str();
  auto verbose = std::make_shared<bool>(false);
  cmd->add_flag("--verbose", *verbose, "log the private farm's scheduling");
  cmd->add_option("--seed", o->seed, "training seed (policy init, minibatches, training-world seeds)")
      ->capture_default_str();
  cmd->add_option("--out", *out, "where the trained policy is written")->capture_default_str();
  cmd->add_option("--work-dir", *work, "checkpoint, learning curve (CSV, PNG) and episode files (default: OUT.train)");
  cmd->add_option("--init", o->init_policy, "start from this policy instead of a fresh network");
  cmd->add_flag("--resume", o->resume, "continue from the work dir's checkpoint");
  const std::map<std::string, navstack::rl::PolicyHead> heads = {{"joint", navstack::rl::PolicyHead::kJoint},
                                                                 {"factored", navstack::rl::PolicyHead::kFactored}};
  CLI::Option* head = cmd->add_option("--head", o->head,
                                      "a fresh policy's head: joint (one logit per action; default) or factored "
                                      "(one per frequency level, summed per action)")
                          ->transform(CLI::CheckedTransformer(heads, CLI::ignore_case));
  cmd->add_option("--learning-rate", o->ppo.learning_rate, "Adam step size")->capture_default_str();
  cmd->add_option("--entropy-coef", o->ppo.entropy_coef, "entropy bonus weight")->capture_default_str();
  cmd->add_option("--target-kl", o->ppo.target_kl,
                  "stop an update's epochs once a minibatch's approximate KL exceeds 1.5 x this (0: off)")
      ->capture_default_str();
  cmd->add_option("--eval-every", o->eval_every,
                  "fly the greedy policy on the fixed evaluation worlds before every N-th update and after the "
                  "last (0: never)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--eval-seeds", o->eval_seeds,
                  "evaluation world seeds (each scenario once per seed, boards in turn; outside training's 100-499)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->callback([o, out, work, verbose, head] {
    if (head->count() > 0 && (o->resume || !o->init_policy.empty())) {
      throw CLI::ValidationError("--head", "shapes a fresh policy; --init and --resume keep their policy's head");
    }
    if (!*verbose) spdlog::set_level(spdlog::level::warn);
    o->out = *out;
    o->work_dir = *work;
    o->progress = true;
    o->catalog = sim::FarmCatalog();
    const train::TrainResult result = train::Train(*o);
    const auto& last = result.iterations.back();
    std::printf("trained %lld iterations: policy %s (mean return %.2f, success %.0f%%, nav cpu %.1f%%)\n",
                static_cast<long long>(last.iteration + 1), out->c_str(), last.mean_return, 100 * last.success_rate,
                last.mean_nav_cpu);
    if (!result.evaluations.empty()) {
      const auto& a = result.evaluations.front();
      const auto& b = result.evaluations.back();
      std::printf("evaluation (greedy, %d fixed worlds): return %.2f after %lld updates -> %.2f after %lld "
                  "(nav cpu %.1f%% -> %.1f%%, flight %.1f s -> %.1f s, success %.0f%% -> %.0f%%)\n",
                  b.episodes, a.mean_return, static_cast<long long>(a.policy_iteration), b.mean_return,
                  static_cast<long long>(b.policy_iteration), a.mean_nav_cpu, b.mean_nav_cpu, a.mean_flight_time,
                  b.mean_flight_time, 100 * a.success_rate, 100 * b.success_rate);
    }
  });
}

}  // namespace enavi::cli
