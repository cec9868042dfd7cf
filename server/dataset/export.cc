#include "server/dataset/export.h"

#include <cstring>
#include <optional>
#include <span>
#include <set>
#include <stdexcept>

#include "api/atomic_file.h"
#include "navstack/rl/json_read.h"
#include "navstack/adapt/policy_state.h"
#include "navstack/rl/nav_rollout.h"
#include "navstack/rl/rollout.h"
#include "server/dataset/npz.h"

namespace enavi::dataset {
namespace {

namespace fs = std::filesystem;
namespace rl = navstack::rl;

struct Column {
  const char* name;
  const char* dtype;  // NumPy dtype, or "U" for a fixed-width string column
  const char* shape;
  const char* meaning;
};

// The arrays of every shard, in order; docs/rl.md documents the same table.
constexpr Column kColumns[] = {
    {"obs", "<f8", "[N, obs_dim]", "raw policy state before the action (the policy normalises it itself)"},
    {"action", "<i4", "[N]", "index into the action grid"},
    {"mask", "|b1", "[N, num_actions]", "feasible actions at this step (constraints C1-C4)"},
    {"reward", "<f8", "[N]", "reward received after the action"},
    {"done", "|b1", "[N]", "true terminal after this step (goal or collision): no value beyond"},
    {"truncated", "|b1", "[N]", "last step of an episode that ended without a terminal (time-out)"},
    {"bootstrap_value", "<f8", "[N]", "V(s_T) after a truncated step, else 0"},
    {"log_prob", "<f8", "[N]", "log pi(action | obs) under the mask, at collection"},
    {"value", "<f8", "[N]", "critic's V(obs) at collection"},
    {"step", "<i4", "[N]", "decision index within the episode"},
    {"episode", "<i4", "[N]", "episode index within the job"},
    {"episode_id", "U", "[N]", "farm episode id"},
    {"board", "U", "[N]", "board profile the episode flew on"},
    {"scenario", "U", "[N]", "scenario id (a registered generator, or custom for a world file)"},
    {"seed", "<u8", "[N]", "world and episode seed"},
    {"policy_hash", "U", "[N]", "SHA-256 of the policy that collected the step"},
};

// A collection job of the learned method: depth images, state and continuous actions.
constexpr Column kNavColumns[] = {
    {"depth", "<u2", "[N, height, width]", "depth / max_depth_m x 65535 (the policy saw depth / 65535)"},
    {"state", "<f8", "[N, 8]", "goal direction (3), goal distance (1), velocity (3), yaw rate (1) in the yaw frame"},
    {"action", "<f8", "[N, 4]", "forward, left, up velocity and yaw rate in [-1, 1] x action_scale, before the clip"},
    {"reward", "<f8", "[N]", "reward received after the action (progress, smoothness, goal and crash terms)"},
    {"done", "|b1", "[N]", "true terminal after this step (goal, collision, out of bounds): no value beyond"},
    {"truncated", "|b1", "[N]", "last step of an episode that ended without a terminal (time-out)"},
    {"log_prob", "<f8", "[N]", "log pi(action | obs) under the policy's Gaussian when sampled; 0 when greedy"},
    {"step", "<i4", "[N]", "decision index within the episode"},
    {"episode", "<i4", "[N]", "episode index within the job"},
    {"episode_id", "U", "[N]", "farm episode id"},
    {"board", "U", "[N]", "board profile the episode flew on"},
    {"scenario", "U", "[N]", "scenario id (a registered generator, or custom for a world file)"},
    {"seed", "<u8", "[N]", "world and episode seed"},
    {"policy_hash", "U", "[N]", "SHA-256 of the policy that collected the step"},
};

nlohmann::json ArraysOf(std::span<const Column> columns) {
  nlohmann::json arrays = nlohmann::json::array();
  for (const Column& c : columns) {
    arrays.push_back({{"name", c.name},
                      {"dtype", std::string(c.dtype) == "U" ? "<U (fixed width)" : c.dtype},
                      {"shape", c.shape},
                      {"meaning", c.meaning}});
  }
  return arrays;
}

template <typename T>
void Append(std::string* data, T v) {
  data->append(reinterpret_cast<const char*>(&v), sizeof v);
}

// Fixed-width UCS-4 strings ('<Un'), NumPy's native string arrays: loadable without pickle.
NpyArray Strings(const std::string& name, const std::vector<std::string>& values) {
  std::size_t width = 1;
  for (const auto& v : values) width = std::max(width, v.size());
  NpyArray a{name, "<U" + std::to_string(width), {values.size()}, {}};
  a.data.reserve(values.size() * width * 4);
  for (const auto& v : values) {
    for (std::size_t i = 0; i < width; ++i) {
      Append(&a.data, static_cast<std::uint32_t>(i < v.size() ? static_cast<unsigned char>(v[i]) : 0));
    }
  }
  return a;
}

// The columns every kind has: where each step came from.
struct Provenance {
  std::string step, episode, seed;
  std::vector<std::string> episode_id, board, scenario, policy_hash;

  void Add(const api::StoredRollout& r, std::size_t t) {
    Append(&step, static_cast<std::int32_t>(t));
    Append(&episode, static_cast<std::int32_t>(r.index));
    Append(&seed, static_cast<std::uint64_t>(r.seed));
    episode_id.push_back(r.episode_id);
    board.push_back(r.board);
    scenario.push_back(r.scenario);
    policy_hash.push_back(r.policy_hash);
  }
  void AppendTo(std::vector<NpyArray>* arrays, std::size_t n) const {
    arrays->push_back({"step", "<i4", {n}, step});
    arrays->push_back({"episode", "<i4", {n}, episode});
    arrays->push_back(Strings("episode_id", episode_id));
    arrays->push_back(Strings("board", board));
    arrays->push_back(Strings("scenario", scenario));
    arrays->push_back({"seed", "<u8", {n}, seed});
    arrays->push_back(Strings("policy_hash", policy_hash));
  }
};

struct Shard {
  std::size_t n = 0;
  std::string obs, action, mask, reward, done, truncated, bootstrap, log_prob, value;
  Provenance from;
  int episodes = 0;
};

struct NavShard {
  std::size_t n = 0;
  std::string depth, state, action, reward, done, truncated, log_prob;
  Provenance from;
  int episodes = 0;
};

void AddEpisode(Shard* s, const api::StoredRollout& r, const rl::Rollout& ro) {
  const std::size_t steps = ro.steps.size();
  for (std::size_t t = 0; t < steps; ++t) {
    const rl::RolloutStep& st = ro.steps[t];
    s->obs.append(reinterpret_cast<const char*>(st.obs.data()), st.obs.size() * sizeof(double));
    Append(&s->action, static_cast<std::int32_t>(st.action));
    for (const std::uint8_t m : st.mask) s->mask.push_back(m ? 1 : 0);
    Append(&s->reward, st.reward);
    s->done.push_back(st.done ? 1 : 0);
    const bool truncated = t + 1 == steps && !st.done;
    s->truncated.push_back(truncated ? 1 : 0);
    Append(&s->bootstrap, truncated ? ro.bootstrap_value : 0.0);
    Append(&s->log_prob, st.log_prob);
    Append(&s->value, st.value);
    s->from.Add(r, t);
  }
  s->n += steps;
  ++s->episodes;
}

void WriteShard(const fs::path& path, const Shard& s, std::size_t obs_dim, std::size_t num_actions) {
  const std::size_t n = s.n;
  std::vector<NpyArray> arrays = {
      {"obs", "<f8", {n, obs_dim}, s.obs},
      {"action", "<i4", {n}, s.action},
      {"mask", "|b1", {n, num_actions}, s.mask},
      {"reward", "<f8", {n}, s.reward},
      {"done", "|b1", {n}, s.done},
      {"truncated", "|b1", {n}, s.truncated},
      {"bootstrap_value", "<f8", {n}, s.bootstrap},
      {"log_prob", "<f8", {n}, s.log_prob},
      {"value", "<f8", {n}, s.value},
  };
  s.from.AppendTo(&arrays, n);
  WriteNpz(path, arrays);
}

void AddNavEpisode(NavShard* s, const api::StoredRollout& r, const rl::NavRollout& ro) {
  const std::size_t steps = ro.steps.size();
  for (std::size_t t = 0; t < steps; ++t) {
    const rl::NavRolloutStep& st = ro.steps[t];
    s->depth.append(reinterpret_cast<const char*>(st.depth.data()), st.depth.size() * sizeof(std::uint16_t));
    s->state.append(reinterpret_cast<const char*>(st.state.data()), st.state.size() * sizeof(double));
    s->action.append(reinterpret_cast<const char*>(st.action.data()), st.action.size() * sizeof(double));
    Append(&s->reward, st.reward);
    s->done.push_back(st.done ? 1 : 0);
    s->truncated.push_back(t + 1 == steps && !st.done ? 1 : 0);
    Append(&s->log_prob, st.log_prob);
    s->from.Add(r, t);
  }
  s->n += steps;
  ++s->episodes;
}

void WriteNavShard(const fs::path& path, const NavShard& s, std::size_t width, std::size_t height) {
  const std::size_t n = s.n;
  std::vector<NpyArray> arrays = {
      {"depth", "<u2", {n, height, width}, s.depth},
      {"state", "<f8", {n, std::size_t{rl::kNavStateSize}}, s.state},
      {"action", "<f8", {n, std::size_t{rl::kNavActionSize}}, s.action},
      {"reward", "<f8", {n}, s.reward},
      {"done", "|b1", {n}, s.done},
      {"truncated", "|b1", {n}, s.truncated},
      {"log_prob", "<f8", {n}, s.log_prob},
  };
  s.from.AppendTo(&arrays, n);
  WriteNpz(path, arrays);
}

}  // namespace

nlohmann::json DatasetSchema(int obs_dim, int num_actions) {
  return {{"format", "enavi-rollout-dataset"},
          {"version", 1},
          {"kind", "frequency"},
          {"obs_dim", obs_dim},
          {"num_actions", num_actions},
          {"observation_features", navstack::PolicyStateFeatureNames()},
          {"arrays", ArraysOf(kColumns)}};
}

nlohmann::json NavDatasetSchema(int width, int height, double max_depth_m) {
  return {{"format", "enavi-rollout-dataset"},
          {"version", 1},
          {"kind", "nav"},
          {"image", {{"width", width}, {"height", height}, {"max_depth_m", max_depth_m}}},
          {"state_features", {"goal_dir_x", "goal_dir_y", "goal_dir_z", "goal_distance", "v_forward", "v_left", "v_up",
                              "yaw_rate"}},
          {"action_names", {"v_forward", "v_left", "v_up", "yaw_rate"}},
          {"arrays", ArraysOf(kNavColumns)}};
}

ExportSummary ExportDataset(const std::vector<api::StoredRollout>& records, const ExportOptions& options) {
  const bool nav = !records.empty() && rl::IsNavRolloutBlob(records.front().rollout);
  const std::size_t shard_steps =
      options.shard_steps > 0 ? options.shard_steps : nav ? kNavShardSteps : kFrequencyShardSteps;
  fs::create_directories(options.out);
  ExportSummary summary;
  std::set<std::string> seen;
  int obs_dim = -1, num_actions = -1;  // nav: width, height
  double max_depth_m = 0;
  nlohmann::json shards = nlohmann::json::array();
  nlohmann::json episodes = nlohmann::json::array();
  Shard shard;
  NavShard nav_shard;
  auto flush = [&] {
    const std::size_t n = nav ? nav_shard.n : shard.n;
    if (n == 0) return;
    char name[32];
    std::snprintf(name, sizeof name, "shard-%05zu.npz", summary.shards.size());
    if (nav) WriteNavShard(options.out / name, nav_shard, static_cast<std::size_t>(obs_dim), static_cast<std::size_t>(num_actions));
    else WriteShard(options.out / name, shard, static_cast<std::size_t>(obs_dim), static_cast<std::size_t>(num_actions));
    shards.push_back({{"file", name}, {"steps", n}, {"episodes", nav ? nav_shard.episodes : shard.episodes}});
    summary.shards.push_back(name);
    shard = Shard{};
    nav_shard = NavShard{};
  };
  for (const api::StoredRollout& r : records) {
    if (!seen.insert(r.episode_id).second) {
      throw std::invalid_argument("episode " + r.episode_id + " appears twice in the job's rollouts");
    }
    const std::string source = "rollout of " + r.episode_id;
    if (rl::IsNavRolloutBlob(r.rollout) != nav)
      throw std::invalid_argument(source + ": a " + (nav ? "frequency" : "nav") + " rollout among the job's " +
                                  (nav ? "nav" : "frequency") + " rollouts");
    std::size_t steps = 0;
    double ret = 0;
    int od = 0, na = 0;
    std::optional<rl::Rollout> ro;
    std::optional<rl::NavRollout> nro;
    if (nav) {
      nro = rl::DecodeNavRollout(r.rollout, source);
      steps = nro->steps.size();
      ret = nro->Return();
      od = nro->width;
      na = nro->height;
    } else {
      ro = rl::DecodeRollout(r.rollout, source);
      steps = ro->steps.size();
      ret = ro->Return();
      if (steps) {
        od = static_cast<int>(ro->steps.front().obs.size());
        na = static_cast<int>(ro->steps.front().mask.size());
      }
    }
    if (steps == 0) continue;
    if (obs_dim < 0) {
      obs_dim = od;
      num_actions = na;
      if (nro) max_depth_m = nro->max_depth_m;
    } else if (od != obs_dim || na != num_actions || (nro && nro->max_depth_m != max_depth_m)) {
      throw std::invalid_argument(source + ": shape differs from the job's first rollout");
    }
    if (nav) AddNavEpisode(&nav_shard, r, *nro);
    else AddEpisode(&shard, r, *ro);
    episodes.push_back({{"episode", r.index}, {"episode_id", r.episode_id}, {"board", r.board},
                        {"scenario", r.scenario}, {"world", r.world}, {"seed", r.seed},
                        {"policy_hash", r.policy_hash}, {"attempt", r.attempt}, {"worker", r.worker},
                        {"steps", steps}, {"return", ret}, {"success", r.success},
                        {"collided", r.collided}, {"flight_time_s", r.flight_time_s},
                        {"nav_cpu_util_pct", r.nav_cpu_util_pct}, {"shard", summary.shards.size()}});
    ++summary.episodes;
    summary.steps += steps;
    if ((nav ? nav_shard.n : shard.n) >= shard_steps) flush();
  }
  if (summary.episodes == 0) throw std::invalid_argument("job " + options.job_id + " has no stored rollouts yet");
  flush();
  nlohmann::json schema = nav ? NavDatasetSchema(obs_dim, num_actions, max_depth_m) : DatasetSchema(obs_dim, num_actions);
  schema["job_id"] = options.job_id;
  schema["episodes"] = summary.episodes;
  schema["steps"] = summary.steps;
  schema["shards"] = shards;
  schema["episode_table"] = episodes;
  api::WriteFileAtomic(options.out / "schema.json", schema.dump(1) + "\n");
  return summary;
}

}  // namespace enavi::dataset
