#include "server/dataset/export.h"

#include <cstring>
#include <set>
#include <stdexcept>

#include "api/atomic_file.h"
#include "navstack/rl/json_read.h"
#include "navstack/adapt/policy_state.h"
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

struct Shard {
  std::size_t n = 0;
  std::string obs, action, mask, reward, done, truncated, bootstrap, log_prob, value, step, episode, seed;
  std::vector<std::string> episode_id, board, scenario, policy_hash;
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
    Append(&s->step, static_cast<std::int32_t>(t));
    Append(&s->episode, static_cast<std::int32_t>(r.index));
    Append(&s->seed, static_cast<std::uint64_t>(r.seed));
    s->episode_id.push_back(r.episode_id);
    s->board.push_back(r.board);
    s->scenario.push_back(r.scenario);
    s->policy_hash.push_back(r.policy_hash);
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
      {"step", "<i4", {n}, s.step},
      {"episode", "<i4", {n}, s.episode},
      Strings("episode_id", s.episode_id),
      Strings("board", s.board),
      Strings("scenario", s.scenario),
      {"seed", "<u8", {n}, s.seed},
      Strings("policy_hash", s.policy_hash),
  };
  WriteNpz(path, arrays);
}

}  // namespace

nlohmann::json DatasetSchema(int obs_dim, int num_actions) {
  nlohmann::json arrays = nlohmann::json::array();
  for (const Column& c : kColumns) {
    arrays.push_back({{"name", c.name},
                      {"dtype", std::string(c.dtype) == "U" ? "<U (fixed width)" : c.dtype},
                      {"shape", c.shape},
                      {"meaning", c.meaning}});
  }
  return {{"format", "enavi-rollout-dataset"},
          {"version", 1},
          {"obs_dim", obs_dim},
          {"num_actions", num_actions},
          {"observation_features", navstack::PolicyStateFeatureNames()},
          {"arrays", arrays}};
}

ExportSummary ExportDataset(const std::vector<api::StoredRollout>& records, const ExportOptions& options) {
  if (options.shard_steps < 1) throw std::invalid_argument("--shard-steps: must be >= 1");
  fs::create_directories(options.out);
  ExportSummary summary;
  std::set<std::string> seen;
  int obs_dim = -1, num_actions = -1;
  nlohmann::json shards = nlohmann::json::array();
  nlohmann::json episodes = nlohmann::json::array();
  Shard shard;
  auto flush = [&] {
    if (shard.n == 0) return;
    char name[32];
    std::snprintf(name, sizeof name, "shard-%05zu.npz", summary.shards.size());
    WriteShard(options.out / name, shard, static_cast<std::size_t>(obs_dim), static_cast<std::size_t>(num_actions));
    shards.push_back({{"file", name}, {"steps", shard.n}, {"episodes", shard.episodes}});
    summary.shards.push_back(name);
    shard = Shard{};
  };
  for (const api::StoredRollout& r : records) {
    if (!seen.insert(r.episode_id).second) {
      throw std::invalid_argument("episode " + r.episode_id + " appears twice in the job's rollouts");
    }
    const rl::Rollout ro = rl::DecodeRollout(r.rollout, "rollout of " + r.episode_id);
    if (ro.steps.empty()) continue;
    const int od = static_cast<int>(ro.steps.front().obs.size());
    const int na = static_cast<int>(ro.steps.front().mask.size());
    if (obs_dim < 0) {
      obs_dim = od;
      num_actions = na;
    } else if (od != obs_dim || na != num_actions) {
      throw std::invalid_argument("rollout of " + r.episode_id + ": shape differs from the job's first rollout");
    }
    AddEpisode(&shard, r, ro);
    episodes.push_back({{"episode", r.index}, {"episode_id", r.episode_id}, {"board", r.board},
                        {"scenario", r.scenario}, {"world", r.world}, {"seed", r.seed},
                        {"policy_hash", r.policy_hash}, {"attempt", r.attempt}, {"worker", r.worker},
                        {"steps", ro.steps.size()}, {"return", ro.Return()}, {"success", r.success},
                        {"collided", r.collided}, {"flight_time_s", r.flight_time_s},
                        {"nav_cpu_util_pct", r.nav_cpu_util_pct}, {"shard", summary.shards.size()}});
    ++summary.episodes;
    summary.steps += ro.steps.size();
    if (shard.n >= options.shard_steps) flush();
  }
  if (summary.episodes == 0) throw std::invalid_argument("job " + options.job_id + " has no stored rollouts yet");
  flush();
  nlohmann::json schema = DatasetSchema(obs_dim, num_actions);
  schema["job_id"] = options.job_id;
  schema["episodes"] = summary.episodes;
  schema["steps"] = summary.steps;
  schema["shards"] = shards;
  schema["episode_table"] = episodes;
  api::WriteFileAtomic(options.out / "schema.json", schema.dump(1) + "\n");
  return summary;
}

}  // namespace enavi::dataset
