#include "workers/sim/episode_child.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "api/atomic_file.h"
#include "api/job_spec.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/nav_rollout.h"
#include "navstack/rl/random.h"
#include "navstack/rl/rollout.h"
#include "workers/sim/nav_stepper.h"

namespace enavi::sim {
namespace {

void CheckSpecFields(const nlohmann::json& j, const std::string& file) {
  if (!j.is_object())
    throw std::invalid_argument(file + ": not an episode spec: expected a JSON object, got " + j.type_name());
  api::EpisodeSpec every;  // every optional field set, so its JSON names all fields
  every.start = every.goal = api::Vec3{};
  every.world_params = {{"k", "v"}};
  every.policy = "p";
  every.overrides = {{"k", 0.0}};
  every.units = every.up = "m";
  every.scale = 2.0;
  every.recenter = true;
  every.model_path = {"d"};
  every.speed_probe = "use";
  every.ros = api::RosStack{};
  every.rosbag_dir = "d";
  every.wind.speed_mps = 1.0;
  every.odometry_noise = "good";
  const nlohmann::json known = every;
  for (const auto& item : j.items()) {
    if (known.contains(item.key())) continue;
    std::string names;
    for (const auto& k : known.items()) names += (names.empty() ? "" : ", ") + k.key();
    throw std::invalid_argument(file + ": " + item.key() + ": unknown field (known: " + names + ")");
  }
}

// A collection episode of the learned method: its policy file's actions (drawn from its Gaussian
// with learned.explore, as the method draws them) supplied decision by decision, so that each
// step's reward is the navigation environment's.
api::EpisodeResult CollectNavRollout(const api::EpisodeSpec& spec, EpisodeOptions options,
                                     navstack::rl::NavRollout* rollout) {
  namespace rl = navstack::rl;
  if (spec.policy.empty()) throw std::invalid_argument("policy: method learned flies a nav policy file");
  const rl::NavPolicyNet net = rl::LoadNavPolicy(spec.policy);
  const auto explore = spec.overrides.find("learned.explore");
  const bool sample = explore != spec.overrides.end() && explore->second > 0;
  rl::Rng rng(rl::NavExploreSeed(spec.seed));
  const auto world = PrepareSpecWorld(spec);
  NavStepper stepper(spec, *world, std::move(options));
  rollout->width = net.width();
  rollout->height = net.height();
  rollout->max_depth_m = net.max_depth_m();
  NavTransition t = stepper.First();
  while (!stepper.finished()) {
    const rl::NavObservation obs{t.depth, t.state};
    rl::SampledNavAction a;
    if (sample) a = rl::SampleNavAction(net, obs, &rng);
    else a.action = net.Forward(obs);
    rl::NavRolloutStep step{rl::QuantizeDepth(t.depth), t.state, a.action, a.log_prob};
    t = stepper.Step(a.action);
    step.reward = t.reward;
    step.done = t.terminated;
    rollout->steps.push_back(std::move(step));
  }
  return stepper.result();
}

}  // namespace

api::EpisodeSpec ReadSpecFile(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::invalid_argument(file + ": cannot read the spec file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(file + ": not an episode spec: " + e.what());
  }
  CheckSpecFields(j, file);
  api::EpisodeSpec spec;
  try {
    spec = j.get<api::EpisodeSpec>();
  } catch (const std::invalid_argument& e) {  // a field of the wrong type, named by the reader
    throw std::invalid_argument(file + ": not an episode spec: " + e.what());
  }
  if (!(spec.timeout_s >= 0 && spec.timeout_s <= api::kMaxTimeoutS))
    throw std::invalid_argument(file + ": timeout_s: must be in [0, " +
                                std::to_string(static_cast<int>(api::kMaxTimeoutS)) + "] s (got " +
                                nlohmann::json(spec.timeout_s).dump() + ")");
  return spec;
}

api::EpisodeResult RunEpisodeChild(const ChildFiles& files, EpisodeOptions options) {
  const api::EpisodeSpec spec = ReadSpecFile(files.spec_file);
  const bool nav = !files.rollout_file.empty() && spec.method == "learned";
  navstack::rl::Rollout rollout;
  navstack::rl::NavRollout nav_rollout;
  if (!files.rollout_file.empty() && !nav) options.rollout = &rollout;
  const api::EpisodeResult result = nav ? CollectNavRollout(spec, std::move(options), &nav_rollout)
                                        : RunEpisode(spec, options);
  if (!files.result_file.empty()) api::WriteFileAtomic(files.result_file, nlohmann::json(result).dump() + "\n");
  if (!files.rollout_file.empty()) {
    const std::string id = spec.world + "-" + std::to_string(spec.seed) + "-" + spec.board;
    const std::map<std::string, double> info = {
        {"success", result.success ? 1.0 : 0.0}, {"collided", result.collided ? 1.0 : 0.0},
        {"flight_time_s", result.flight_time_s}, {"nav_cpu_util_pct", result.nav_cpu_util_pct}};
    if (nav) {
      nav_rollout.id = id;
      nav_rollout.info = info;
      api::WriteFileAtomic(files.rollout_file, navstack::rl::EncodeNavRollout(nav_rollout));
    } else {
      rollout.id = id;
      rollout.info = info;
      api::WriteFileAtomic(files.rollout_file, navstack::rl::SerializeRollout(rollout));
    }
  }
  return result;
}

}  // namespace enavi::sim
