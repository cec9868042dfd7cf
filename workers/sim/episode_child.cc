#include "workers/sim/episode_child.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "api/atomic_file.h"
#include "api/job_spec.h"
#include "navstack/rl/rollout.h"

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
  navstack::rl::Rollout rollout;
  if (!files.rollout_file.empty()) options.rollout = &rollout;
  const api::EpisodeResult result = RunEpisode(spec, options);
  if (!files.result_file.empty()) api::WriteFileAtomic(files.result_file, nlohmann::json(result).dump() + "\n");
  if (!files.rollout_file.empty()) {
    rollout.id = spec.world + "-" + std::to_string(spec.seed) + "-" + spec.board;
    rollout.info = {{"success", result.success ? 1.0 : 0.0}, {"collided", result.collided ? 1.0 : 0.0},
                    {"flight_time_s", result.flight_time_s}, {"nav_cpu_util_pct", result.nav_cpu_util_pct}};
    api::WriteFileAtomic(files.rollout_file, navstack::rl::SerializeRollout(rollout));
  }
  return result;
}

}  // namespace enavi::sim
