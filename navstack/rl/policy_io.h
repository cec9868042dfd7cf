#pragma once
// Policy file: a trained actor-critic with everything needed to use it (architecture, action grid,
// observation layout and normalisation), as versioned JSON.
//
//   {
//     "format": "enavi-frequency-policy", "version": 1,
//     "architecture": {"obs_dim": 16, "num_actions": 189, "hidden": [150, 150],
//                      "activation": "tanh", "actor_output": "masked_categorical_logits",
//                      "critic_output": "state_value"},
//     "observation": {"features": ["eci", ...],
//                     "normaliser": {"mean": [...], "var": [...], "count": n, "clip": 5, "epsilon": 1e-8}},
//     "action_grid": {"order": ["f_per", "f_col", "f_dif"], "unit": "Hz",
//                     "actions": [[1, 0, 0], ...]},          (or null for a generic policy)
//     "actor":  {"layers": [{"in": 16, "out": 150, "weights": [[row 0], ...], "bias": [...]}, ...]},
//     "critic": {"layers": [...]},
//     "metadata": {...}                                        (free-form: how it was trained)
//   }
//
// Doubles are written in shortest round-trip form, so save -> load is bit-exact.

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "navstack/adapt/action_grid.h"
#include "navstack/rl/policy.h"

namespace enavi::navstack::rl {

inline constexpr const char* kPolicyFormat = "enavi-frequency-policy";
inline constexpr int kPolicyVersion = 1;

/// A policy and what it means.
struct PolicyFile {
  ActorCritic net;
  /// Names of the observation features, one per input (PolicyStateFeatureNames() for E-Navi).
  std::vector<std::string> feature_names;
  /// Frequency triple of each action (required for the E-Navi frequency adapter; generic
  /// policies, e.g. in tests, may leave it empty).
  std::optional<ActionGrid> action_grid;
  nlohmann::json metadata = nlohmann::json::object();
};

/// A freshly initialised E-Navi frequency policy: PolicyStateFeatureNames() inputs, one output per
/// grid action, orthogonal weights from `seed`.
PolicyFile MakeFrequencyPolicy(const ActionGrid& grid, std::uint64_t seed,
                               const std::vector<int>& hidden = {150, 150});

/// @throws std::logic_error when the parts disagree (feature count vs obs_dim, grid size vs
///   num_actions): a program bug, not bad input.
nlohmann::json PolicyToJson(const PolicyFile& policy);
/// @throws std::invalid_argument "<source>: <field>: <reason>" for a wrong format or version,
///   a missing field, a wrong shape, a non-finite number or inconsistent parts.
PolicyFile PolicyFromJson(const nlohmann::json& j, const std::string& source);

/// Writes atomically (temporary file + rename). @throws std::runtime_error on I/O failure.
void SavePolicyFile(const std::string& path, const PolicyFile& policy);
/// @throws std::invalid_argument naming the file (and field) when it is missing, truncated, not
///   JSON, or fails PolicyFromJson's checks.
PolicyFile LoadPolicyFile(const std::string& path);
/// LoadPolicyFile plus the E-Navi contract: an action grid is present and the features are
/// exactly PolicyStateFeatureNames().
PolicyFile LoadFrequencyPolicy(const std::string& path);
/// The E-Navi contract above. @throws std::invalid_argument naming `source`.
void CheckFrequencyPolicy(const PolicyFile& policy, const std::string& source);
/// PolicyFromJson of `text` plus the E-Navi contract.
PolicyFile FrequencyPolicyFromText(const std::string& text, const std::string& source);
/// The canonical bytes of a policy (compact JSON): what the farm distributes and hashes, so
/// the same network always has the same content hash.
std::string CanonicalPolicyText(const PolicyFile& policy);

}  // namespace enavi::navstack::rl
