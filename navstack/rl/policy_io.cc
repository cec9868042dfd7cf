#include "navstack/rl/policy_io.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "api/atomic_file.h"
#include "navstack/adapt/policy_state.h"
#include "navstack/rl/json_read.h"
#include "navstack/rl/weight_block.h"

namespace enavi::navstack::rl {
namespace {

using detail::JsonReader;
using nlohmann::json;

// Visits every weight of `net` in kPolicyParameterLayout order; `visit(value, name)` gets the
// weight and a function that spells its field name (built only when an error needs it).
template <typename Net, typename Visit>
void ForEachParameter(Net& net, Visit&& visit) {
  const auto each = [&](auto& mlp, const char* which) {
    for (int l = 0; l < mlp.num_layers(); ++l) {
      const std::string layer = std::string(which) + ".layers[" + std::to_string(l) + "]";
      auto W = mlp.W(l);
      for (Eigen::Index i = 0; i < W.rows(); ++i) {
        for (Eigen::Index j = 0; j < W.cols(); ++j) {
          visit(W(i, j), [&] { return layer + ".weights[" + std::to_string(i) + "][" + std::to_string(j) + "]"; });
        }
      }
      auto b = mlp.b(l);
      for (Eigen::Index i = 0; i < b.size(); ++i) {
        visit(b[i], [&] { return layer + ".bias[" + std::to_string(i) + "]"; });
      }
    }
  };
  each(net.actor(), "actor");
  each(net.critic(), "critic");
}

Eigen::Index ParameterCount(const ActorCritic& net) { return net.actor().num_params() + net.critic().num_params(); }

// The weights in kPolicyParameterLayout order, and the name of weight i (for errors).
std::vector<double> Weights(const ActorCritic& net) {
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(ParameterCount(net)));
  ForEachParameter(net, [&](double v, const auto&) { values.push_back(v); });
  return values;
}
detail::WeightName WeightNames(const ActorCritic& net) {
  return [&net](std::size_t i) {
    std::string name;
    std::size_t k = 0;
    ForEachParameter(net, [&](double, const auto& spell) {
      if (k++ == i) name = spell();
    });
    return name;
  };
}

json ParametersToJson(const ActorCritic& net, WeightPrecision precision) {
  return detail::EncodeWeights(Weights(net), precision, kPolicyParameterLayout, WeightNames(net));
}

// Version 2: the "parameters" block into `net`, whose shapes the architecture already fixed.
void ParametersFromJson(const json& j, const JsonReader& r, ActorCritic* net) {
  const std::vector<double> values = detail::DecodeWeights(
      j, r, "parameters", static_cast<std::size_t>(ParameterCount(*net)), kPolicyParameterLayout, WeightNames(*net));
  std::size_t at = 0;
  ForEachParameter(*net, [&](double& v, const auto&) { v = values[at++]; });
}

// Version 1: the layers of one network as nested arrays into `mlp`, whose sizes are already fixed
// by the architecture.
void MlpFromJson(const json& j, const std::string& field, const JsonReader& r, Mlp* mlp) {
  const json& layers = r.Array(r.Field(j, field, "layers"), field + ".layers");
  if (static_cast<int>(layers.size()) != mlp->num_layers()) {
    r.Fail(field + ".layers", "expected " + std::to_string(mlp->num_layers()) +
                                  " layers (architecture), got " + std::to_string(layers.size()));
  }
  for (int l = 0; l < mlp->num_layers(); ++l) {
    const std::string lf = JsonReader::Index(field + ".layers", static_cast<std::size_t>(l));
    const json& lj = layers[static_cast<std::size_t>(l)];
    const int in = mlp->sizes()[static_cast<std::size_t>(l)];
    const int out = mlp->sizes()[static_cast<std::size_t>(l) + 1];
    if (r.Integer(r.Field(lj, lf, "in"), lf + ".in") != in) {
      r.Fail(lf + ".in", "expected " + std::to_string(in) + " (architecture)");
    }
    if (r.Integer(r.Field(lj, lf, "out"), lf + ".out") != out) {
      r.Fail(lf + ".out", "expected " + std::to_string(out) + " (architecture)");
    }
    const json& rows = r.Array(r.Field(lj, lf, "weights"), lf + ".weights");
    if (static_cast<int>(rows.size()) != out) {
      r.Fail(lf + ".weights", "expected " + std::to_string(out) + " rows, got " +
                                  std::to_string(rows.size()));
    }
    auto W = mlp->W(l);
    for (int i = 0; i < out; ++i) {
      W.row(i) = r.Vector(rows[static_cast<std::size_t>(i)],
                          JsonReader::Index(lf + ".weights", static_cast<std::size_t>(i)), in)
                     .transpose();
    }
    mlp->b(l) = r.Vector(r.Field(lj, lf, "bias"), lf + ".bias", out);
  }
}

constexpr const char* kJointHead = "masked_categorical_logits";
constexpr const char* kFactoredHead = "factored_masked_categorical_logits";

// The factored head over a grid: the levels of each frequency, ascending, f_per's first.
void FactorHead(const ActionGrid& grid, ActorCriticConfig* config) {
  using Component = double TaskFrequencies::*;
  const Component components[] = {&TaskFrequencies::f_per, &TaskFrequencies::f_col, &TaskFrequencies::f_dif};
  config->action_terms.assign(static_cast<std::size_t>(grid.size()), {});
  int offset = 0;
  for (const Component c : components) {
    std::vector<double> levels;
    for (const TaskFrequencies& f : grid.actions()) levels.push_back(f.*c);
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    for (int a = 0; a < grid.size(); ++a) {
      const auto level = std::lower_bound(levels.begin(), levels.end(), grid.At(a).*c) - levels.begin();
      config->action_terms[static_cast<std::size_t>(a)].push_back(offset + static_cast<int>(level));
    }
    offset += static_cast<int>(levels.size());
  }
  config->head_outputs = offset;
}

void CheckConsistent(const PolicyFile& p) {
  if (static_cast<int>(p.feature_names.size()) != p.net.obs_dim()) {
    throw std::logic_error("PolicyFile: " + std::to_string(p.feature_names.size()) +
                           " feature names for obs_dim " + std::to_string(p.net.obs_dim()));
  }
  if (p.action_grid && p.action_grid->size() != p.net.num_actions()) {
    throw std::logic_error("PolicyFile: action grid has " + std::to_string(p.action_grid->size()) +
                           " actions, the network " + std::to_string(p.net.num_actions()));
  }
  if (p.net.config().factored()) {
    ActorCriticConfig expected;
    if (p.action_grid) FactorHead(*p.action_grid, &expected);
    if (expected.action_terms != p.net.config().action_terms) {
      throw std::logic_error("PolicyFile: a factored head must be the action grid's (f_per, f_col, f_dif) levels");
    }
  }
}

}  // namespace

PolicyFile MakeFrequencyPolicy(const ActionGrid& grid, std::uint64_t seed, PolicyHead head,
                               const std::vector<int>& hidden) {
  ActorCriticConfig config{kPolicyStateDim, grid.size(), hidden};
  if (head == PolicyHead::kFactored) FactorHead(grid, &config);
  PolicyFile p{ActorCritic(config), PolicyStateFeatureNames(), grid, json::object()};
  Rng rng(seed);
  p.net.InitializeWeights(&rng);
  return p;
}

json PolicyToJson(const PolicyFile& p, WeightPrecision precision) {
  CheckConsistent(p);
  const ActorCritic& net = p.net;
  json j;
  j["format"] = kPolicyFormat;
  j["version"] = kPolicyVersion;
  j["architecture"] = {{"obs_dim", net.obs_dim()},
                       {"num_actions", net.num_actions()},
                       {"hidden", net.config().hidden},
                       {"activation", "tanh"},
                       {"actor_output", net.config().factored() ? kFactoredHead : kJointHead},
                       {"critic_output", "state_value"}};
  const ObservationNormaliser& norm = net.normaliser();
  j["observation"] = {{"features", p.feature_names},
                      {"normaliser",
                       {{"mean", detail::ToJson(norm.mean)},
                        {"var", detail::ToJson(norm.var)},
                        {"count", norm.count},
                        {"clip", norm.clip},
                        {"epsilon", norm.epsilon}}}};
  if (p.action_grid) {
    json actions = json::array();
    for (const TaskFrequencies& f : p.action_grid->actions()) {
      actions.push_back({f.f_per, f.f_col, f.f_dif});
    }
    j["action_grid"] = {{"order", {"f_per", "f_col", "f_dif"}}, {"unit", "Hz"}, {"actions", actions}};
  } else {
    j["action_grid"] = nullptr;
  }
  j["parameters"] = ParametersToJson(net, precision);
  j["metadata"] = p.metadata;
  return j;
}

PolicyFile PolicyFromJson(const json& j, const std::string& source) {
  const JsonReader r(source);
  r.Object(j, "");
  const std::string format = r.String(r.Field(j, "", "format"), "format");
  if (format != kPolicyFormat) {
    r.Fail("format", "expected \"" + std::string(kPolicyFormat) + "\", got \"" + format + "\"");
  }
  const std::int64_t version = r.Integer(r.Field(j, "", "version"), "version");
  if (version != 1 && version != kPolicyVersion) {
    r.Fail("version", "unsupported version " + std::to_string(version) + " (this build reads 1 and " +
                          std::to_string(kPolicyVersion) + ")");
  }

  // Architecture first: it fixes every shape checked below.
  const json& arch = r.Object(r.Field(j, "", "architecture"), "architecture");
  constexpr std::int64_t kMaxWidth = 1 << 16;
  const auto size_field = [&](const json& v, const std::string& f) {
    const std::int64_t n = r.Integer(v, f);
    if (n < 1 || n > kMaxWidth) r.Fail(f, "must be in [1, " + std::to_string(kMaxWidth) + "]");
    return static_cast<int>(n);
  };
  ActorCriticConfig config;
  config.obs_dim = size_field(r.Field(arch, "architecture", "obs_dim"), "architecture.obs_dim");
  config.num_actions =
      size_field(r.Field(arch, "architecture", "num_actions"), "architecture.num_actions");
  const json& hidden = r.Array(r.Field(arch, "architecture", "hidden"), "architecture.hidden");
  config.hidden.clear();
  for (std::size_t i = 0; i < hidden.size(); ++i) {
    config.hidden.push_back(size_field(hidden[i], JsonReader::Index("architecture.hidden", i)));
  }
  // Bound the allocation a corrupt header could ask for before any weight is read.
  constexpr double kMaxParams = 1e7;
  double num_params = 0.0;
  for (int out : {config.num_actions, 1}) {
    int in = config.obs_dim;
    for (int h : config.hidden) {
      num_params += (in + 1.0) * h;
      in = h;
    }
    num_params += (in + 1.0) * out;
  }
  if (num_params > kMaxParams) {
    r.Fail("architecture", "network too large (" + std::to_string(num_params) +
                               " parameters, at most 1e7)");
  }
  const std::string activation =
      r.String(r.Field(arch, "architecture", "activation"), "architecture.activation");
  if (activation != "tanh") r.Fail("architecture.activation", "only \"tanh\" is supported");

  // Action grid (optional: null for generic policies).
  std::optional<ActionGrid> action_grid;
  const json& grid = r.Field(j, "", "action_grid");
  if (!grid.is_null()) {
    r.Object(grid, "action_grid");
    const json& order = r.Field(grid, "action_grid", "order");
    if (order != json({"f_per", "f_col", "f_dif"})) {
      r.Fail("action_grid.order", "expected [\"f_per\", \"f_col\", \"f_dif\"]");
    }
    if (r.String(r.Field(grid, "action_grid", "unit"), "action_grid.unit") != "Hz") {
      r.Fail("action_grid.unit", "expected \"Hz\"");
    }
    const json& actions = r.Array(r.Field(grid, "action_grid", "actions"), "action_grid.actions");
    if (static_cast<int>(actions.size()) != config.num_actions) {
      r.Fail("action_grid.actions", "expected " + std::to_string(config.num_actions) +
                                        " actions (num_actions), got " +
                                        std::to_string(actions.size()));
    }
    std::vector<TaskFrequencies> triples;
    for (std::size_t i = 0; i < actions.size(); ++i) {
      const Eigen::VectorXd f = r.Vector(actions[i], JsonReader::Index("action_grid.actions", i), 3);
      triples.push_back({f[0], f[1], f[2]});
    }
    action_grid = ActionGrid::FromTriples(std::move(triples), source + ": action_grid.actions");
  }

  // The head: joint, or factored over the grid's levels (so the grid must be there).
  const json* head = arch.contains("actor_output") || version != 1 ? &r.Field(arch, "architecture", "actor_output") : nullptr;
  const std::string head_name = head ? r.String(*head, "architecture.actor_output") : kJointHead;
  if (head_name == kFactoredHead) {
    if (!action_grid) r.Fail("architecture.actor_output", "a factored head needs the action_grid");
    FactorHead(*action_grid, &config);
  } else if (head_name != kJointHead) {
    r.Fail("architecture.actor_output", "expected \"" + std::string(kJointHead) + "\" or \"" +
                                            kFactoredHead + "\", got \"" + head_name + "\"");
  }

  // Observation layout and normalisation.
  const json& obs = r.Object(r.Field(j, "", "observation"), "observation");
  const json& features = r.Array(r.Field(obs, "observation", "features"), "observation.features");
  if (static_cast<int>(features.size()) != config.obs_dim) {
    r.Fail("observation.features", "expected " + std::to_string(config.obs_dim) +
                                       " names (obs_dim), got " + std::to_string(features.size()));
  }
  PolicyFile p{ActorCritic(config), {}, std::move(action_grid), json::object()};
  for (std::size_t i = 0; i < features.size(); ++i) {
    p.feature_names.push_back(r.String(features[i], JsonReader::Index("observation.features", i)));
  }
  const std::string nf = "observation.normaliser";
  const json& nj = r.Object(r.Field(obs, "observation", "normaliser"), nf);
  ObservationNormaliser& norm = p.net.normaliser();
  norm.mean = r.Vector(r.Field(nj, nf, "mean"), nf + ".mean", config.obs_dim);
  norm.var = r.Vector(r.Field(nj, nf, "var"), nf + ".var", config.obs_dim);
  if ((norm.var.array() < 0.0).any()) r.Fail(nf + ".var", "variances must be >= 0");
  norm.count = r.Number(r.Field(nj, nf, "count"), nf + ".count");
  if (norm.count < 0.0) r.Fail(nf + ".count", "must be >= 0");
  norm.clip = r.Number(r.Field(nj, nf, "clip"), nf + ".clip");
  if (!(norm.clip > 0.0)) r.Fail(nf + ".clip", "must be > 0");
  norm.epsilon = r.Number(r.Field(nj, nf, "epsilon"), nf + ".epsilon");
  if (!(norm.epsilon > 0.0)) r.Fail(nf + ".epsilon", "must be > 0");

  if (version == 1) {
    MlpFromJson(r.Field(j, "", "actor"), "actor", r, &p.net.actor());
    MlpFromJson(r.Field(j, "", "critic"), "critic", r, &p.net.critic());
  } else {
    ParametersFromJson(r.Field(j, "", "parameters"), r, &p.net);
  }
  p.metadata = r.Object(r.Field(j, "", "metadata"), "metadata");
  return p;
}

void SavePolicyFile(const std::string& path, const PolicyFile& policy) {
  api::WriteFileAtomic(path, PolicyToJson(policy, WeightPrecision::kFloat32).dump() + "\n");
}

PolicyFile LoadPolicyFile(const std::string& path) {
  const std::string source = "policy file '" + path + "'";
  return PolicyFromJson(detail::ReadJsonFile(path, "policy file"), source);
}

PolicyFile LoadFrequencyPolicy(const std::string& path) {
  PolicyFile p = LoadPolicyFile(path);
  CheckFrequencyPolicy(p, "policy file '" + path + "'");
  return p;
}

PolicyFile FrequencyPolicyFromText(const std::string& text, const std::string& source) {
  PolicyFile p = PolicyFromJson(detail::ParseJson(text, source), source);
  CheckFrequencyPolicy(p, source);
  return p;
}

std::string CanonicalPolicyText(const PolicyFile& policy) {
  return PolicyToJson(policy, WeightPrecision::kFloat64).dump();
}

void CheckFrequencyPolicy(const PolicyFile& p, const std::string& source) {
  if (!p.action_grid) {
    throw std::invalid_argument(source + ": action_grid: required for the frequency adapter");
  }
  if (p.feature_names != PolicyStateFeatureNames()) {
    throw std::invalid_argument(source + ": observation.features: do not match this build's "
                                "policy state (kPolicyStateDim = " +
                                std::to_string(kPolicyStateDim) + " features, see policy_state.h)");
  }
}

}  // namespace enavi::navstack::rl
