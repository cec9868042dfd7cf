#include "navstack/rl/rollout.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "navstack/rl/blob_io.h"
#include "navstack/rl/json_read.h"

namespace enavi::navstack::rl {
namespace {

constexpr const char* kRolloutFormat = "enavi-rollout";
constexpr int kRolloutVersion = 1;

}  // namespace

double Rollout::Return() const {
  double r = 0.0;
  for (const RolloutStep& s : steps) r += s.reward;
  return r;
}

void ComputeGae(const Rollout& rollout, double gamma, double lambda,
                Eigen::Ref<Eigen::VectorXd> advantages, Eigen::Ref<Eigen::VectorXd> returns) {
  const auto n = static_cast<Eigen::Index>(rollout.steps.size());
  if (advantages.size() != n || returns.size() != n) {
    throw std::logic_error("ComputeGae: output size does not match the rollout");
  }
  double gae = 0.0;
  for (Eigen::Index t = n - 1; t >= 0; --t) {
    const RolloutStep& s = rollout.steps[static_cast<std::size_t>(t)];
    const double next_value =
        s.done ? 0.0 : (t == n - 1 ? rollout.bootstrap_value : rollout.steps[static_cast<std::size_t>(t + 1)].value);
    const double delta = s.reward + gamma * next_value - s.value;
    gae = delta + (s.done ? 0.0 : gamma * lambda * gae);
    advantages[t] = gae;
    returns[t] = gae + s.value;
  }
}

nlohmann::json RolloutToJson(const Rollout& rollout) {
  nlohmann::json j;
  j["format"] = kRolloutFormat;
  j["version"] = kRolloutVersion;
  const bool empty = rollout.steps.empty();
  j["obs_dim"] = empty ? 0 : rollout.steps.front().obs.size();
  j["num_actions"] = empty ? 0 : rollout.steps.front().mask.size();
  j["id"] = rollout.id;
  j["policy_iteration"] = rollout.policy_iteration;
  j["bootstrap_value"] = rollout.bootstrap_value;
  j["info"] = nlohmann::json::object();
  for (const auto& [k, v] : rollout.info) j["info"][k] = v;
  nlohmann::json steps = nlohmann::json::array();
  for (const RolloutStep& s : rollout.steps) {
    std::string mask(s.mask.size(), '0');
    for (std::size_t i = 0; i < s.mask.size(); ++i) mask[i] = s.mask[i] ? '1' : '0';
    steps.push_back({{"obs", detail::ToJson(s.obs)},
                     {"action", s.action},
                     {"mask", mask},
                     {"log_prob", s.log_prob},
                     {"value", s.value},
                     {"reward", s.reward},
                     {"done", s.done}});
  }
  j["steps"] = std::move(steps);
  return j;
}

Rollout RolloutFromJson(const nlohmann::json& j, const std::string& source) {
  const detail::JsonReader r(source);
  r.Object(j, "");
  if (r.String(r.Field(j, "", "format"), "format") != kRolloutFormat) {
    r.Fail("format", std::string("expected \"") + kRolloutFormat + "\"");
  }
  const std::int64_t version = r.Integer(r.Field(j, "", "version"), "version");
  if (version != kRolloutVersion) {
    r.Fail("version", "unsupported version " + std::to_string(version) + " (this build reads " +
                          std::to_string(kRolloutVersion) + ")");
  }
  const std::int64_t obs_dim = r.Integer(r.Field(j, "", "obs_dim"), "obs_dim");
  const std::int64_t num_actions = r.Integer(r.Field(j, "", "num_actions"), "num_actions");
  if (obs_dim < 0 || num_actions < 0) r.Fail("obs_dim", "sizes must be >= 0");

  Rollout out;
  out.id = r.String(r.Field(j, "", "id"), "id");
  out.policy_iteration = r.Integer(r.Field(j, "", "policy_iteration"), "policy_iteration");
  out.bootstrap_value = r.Number(r.Field(j, "", "bootstrap_value"), "bootstrap_value");
  const nlohmann::json& info = r.Object(r.Field(j, "", "info"), "info");
  for (auto it = info.begin(); it != info.end(); ++it) {
    out.info[it.key()] = r.Number(it.value(), "info." + it.key());
  }
  const nlohmann::json& steps = r.Array(r.Field(j, "", "steps"), "steps");
  if (!steps.empty() && (obs_dim < 1 || num_actions < 1)) {
    r.Fail("obs_dim", "must be >= 1 when there are steps");
  }
  out.steps.reserve(steps.size());
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::string f = detail::JsonReader::Index("steps", i);
    const nlohmann::json& sj = steps[i];
    RolloutStep s;
    s.obs = r.Vector(r.Field(sj, f, "obs"), f + ".obs", obs_dim);
    const std::string mask = r.String(r.Field(sj, f, "mask"), f + ".mask");
    if (static_cast<std::int64_t>(mask.size()) != num_actions) {
      r.Fail(f + ".mask", "expected " + std::to_string(num_actions) + " characters");
    }
    s.mask.resize(mask.size());
    for (std::size_t k = 0; k < mask.size(); ++k) {
      if (mask[k] != '0' && mask[k] != '1') r.Fail(f + ".mask", "characters must be '0' or '1'");
      s.mask[k] = mask[k] == '1' ? 1 : 0;
    }
    const std::int64_t action = r.Integer(r.Field(sj, f, "action"), f + ".action");
    if (action < 0 || action >= num_actions || !s.mask[static_cast<std::size_t>(action)]) {
      r.Fail(f + ".action", "action " + std::to_string(action) + " is outside the mask");
    }
    s.action = static_cast<int>(action);
    s.log_prob = r.Number(r.Field(sj, f, "log_prob"), f + ".log_prob");
    if (s.log_prob > 0.0) r.Fail(f + ".log_prob", "a log-probability must be <= 0");
    s.value = r.Number(r.Field(sj, f, "value"), f + ".value");
    s.reward = r.Number(r.Field(sj, f, "reward"), f + ".reward");
    s.done = r.Bool(r.Field(sj, f, "done"), f + ".done");
    out.steps.push_back(std::move(s));
  }
  return out;
}

std::string SerializeRollout(const Rollout& rollout) { return RolloutToJson(rollout).dump(); }

Rollout DeserializeRollout(const std::string& text, const std::string& source) {
  return RolloutFromJson(detail::ParseJson(text, source), source);
}

namespace {

constexpr char kBinaryMagic[4] = {'E', 'N', 'R', '1'};

}  // namespace

using detail::BlobReader;
using detail::Put;

std::string EncodeRollout(const Rollout& rollout) {
  const std::uint32_t obs_dim = rollout.steps.empty() ? 0 : static_cast<std::uint32_t>(rollout.steps.front().obs.size());
  const std::uint32_t num_actions = rollout.steps.empty() ? 0 : static_cast<std::uint32_t>(rollout.steps.front().mask.size());
  const std::size_t mask_bytes = (num_actions + 7) / 8;
  std::string out(kBinaryMagic, 4);
  out.reserve(64 + rollout.steps.size() * (obs_dim * 8 + mask_bytes + 29));
  Put(&out, obs_dim);
  Put(&out, num_actions);
  Put(&out, static_cast<std::uint32_t>(rollout.steps.size()));
  Put(&out, rollout.bootstrap_value);
  Put(&out, static_cast<std::int64_t>(rollout.policy_iteration));
  detail::PutIdAndInfo(&out, rollout.id, rollout.info);
  for (const RolloutStep& s : rollout.steps) {
    if (s.obs.size() != obs_dim || s.mask.size() != num_actions) {
      throw std::logic_error("EncodeRollout: steps of different shapes");
    }
    out.append(reinterpret_cast<const char*>(s.obs.data()), obs_dim * sizeof(double));
    Put(&out, static_cast<std::int32_t>(s.action));
    std::string mask(mask_bytes, '\0');
    for (std::size_t i = 0; i < num_actions; ++i) {
      if (s.mask[i]) mask[i / 8] = static_cast<char>(mask[i / 8] | (1 << (i % 8)));
    }
    out += mask;
    Put(&out, s.log_prob);
    Put(&out, s.value);
    Put(&out, s.reward);
    Put(&out, static_cast<std::uint8_t>(s.done ? 1 : 0));
  }
  return out;
}

Rollout DecodeRollout(std::string_view bytes, const std::string& source) {
  BlobReader r(bytes, source);
  if (r.Bytes(4, "magic") != std::string_view(kBinaryMagic, 4)) r.Fail("magic", "not an ENR1 rollout");
  const auto obs_dim = r.Get<std::uint32_t>("obs_dim");
  const auto num_actions = r.Get<std::uint32_t>("num_actions");
  const auto steps = r.Get<std::uint32_t>("steps");
  if (steps > 0 && (obs_dim < 1 || num_actions < 1)) r.Fail("obs_dim", "must be >= 1 when there are steps");
  if (obs_dim > 4096 || num_actions > 65536) r.Fail("obs_dim", "implausible shape");
  const std::size_t mask_bytes = (num_actions + 7) / 8;
  const std::size_t step_bytes = obs_dim * 8 + 4 + mask_bytes + 3 * 8 + 1;
  Rollout out;
  out.bootstrap_value = r.Finite("bootstrap_value");
  out.policy_iteration = r.Get<std::int64_t>("policy_iteration");
  detail::ReadIdAndInfo(&r, &out.id, &out.info);
  if (static_cast<std::size_t>(steps) * step_bytes != r.left()) {
    r.Fail("steps", std::to_string(steps) + " steps need " + std::to_string(steps * step_bytes) +
                        " bytes, " + std::to_string(r.left()) + " left");
  }
  out.steps.resize(steps);
  for (std::uint32_t t = 0; t < steps; ++t) {
    RolloutStep& s = out.steps[t];
    s.obs.resize(obs_dim);
    for (std::uint32_t k = 0; k < obs_dim; ++k) s.obs[k] = r.Finite("obs");
    s.action = r.Get<std::int32_t>("action");
    const std::string_view mask = r.Bytes(mask_bytes, "mask");
    s.mask.resize(num_actions);
    for (std::size_t i = 0; i < num_actions; ++i) s.mask[i] = (mask[i / 8] >> (i % 8)) & 1;
    if (s.action < 0 || static_cast<std::uint32_t>(s.action) >= num_actions || !s.mask[static_cast<std::size_t>(s.action)]) {
      r.Fail("steps[" + std::to_string(t) + "].action", "action " + std::to_string(s.action) + " is outside the mask");
    }
    s.log_prob = r.Finite("log_prob");
    if (s.log_prob > 0.0) r.Fail("steps[" + std::to_string(t) + "].log_prob", "a log-probability must be <= 0");
    s.value = r.Finite("value");
    s.reward = r.Finite("reward");
    const auto done = r.Get<std::uint8_t>("done");
    if (done > 1) r.Fail("steps[" + std::to_string(t) + "].done", "must be 0 or 1");
    s.done = done == 1;
  }
  return out;
}

}  // namespace enavi::navstack::rl
