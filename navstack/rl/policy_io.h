#pragma once
// Policy file: a trained actor-critic with everything needed to use it (architecture, action grid,
// observation layout and normalisation), as versioned minified JSON with the weights packed in
// one base64 block.
//
//   {
//     "format": "enavi-frequency-policy", "version": 2,
//     "architecture": {"obs_dim": 16, "num_actions": 189, "hidden": [150, 150],
//                      "activation": "tanh", "actor_output": "masked_categorical_logits",
//                      "critic_output": "state_value"},
//       (actor_output "factored_masked_categorical_logits": one output per level of f_per, f_col
//        and f_dif, in that order and each ascending, as the action grid's triples use them; an
//        action's logit is the sum of its three levels' (policy.h); it needs the action grid)
//     "observation": {"features": ["eci", ...],
//                     "normaliser": {"mean": [...], "var": [...], "count": n, "clip": 5, "epsilon": 1e-8}},
//     "action_grid": {"order": ["f_per", "f_col", "f_dif"], "unit": "Hz",
//                     "actions": [[1, 0, 0], ...]},          (or null for a generic policy)
//     "parameters": {"dtype": "float32", "byte_order": "little", "encoding": "base64",
//                    "layout": kPolicyParameterLayout, "count": 79090,
//                    "sha256": "<hex digest of the decoded bytes>", "data": "<base64>"},
//     "metadata": {...}                                        (free-form: how it was trained)
//   }
//
// Why JSON with a base64 block rather than a binary file: the header stays readable and goes
// through the one validated JSON reader (errors name file and field), and a policy still travels
// as text inside job specs, the HTTP API and DDS samples. Packing the weights is what makes it
// small (4 bytes a weight, 5.3 in base64, against ~22 in pretty-printed decimal JSON).
//
// Policy files on disk hold float32 weights (SavePolicyFile): the network then computes in
// double from exactly those values, so a file flies the same wherever it is loaded.
// Checkpoints and the text the farm distributes during training hold float64 (bit-exact: a
// resumed run and the workers' rollouts use the learner's very network).
// Version 1 files (the weights as nested decimal arrays, "actor"/"critic" layers) still load;
// `enavi policy convert OLD --out NEW` rewrites one as version 2.

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "navstack/adapt/action_grid.h"
#include "navstack/rl/policy.h"
#include "navstack/rl/weight_block.h"

namespace enavi::navstack::rl {

inline constexpr const char* kPolicyFormat = "enavi-frequency-policy";
inline constexpr int kPolicyVersion = 2;
/// The order of the weights in the "parameters" block.
inline constexpr const char* kPolicyParameterLayout =
    "actor then critic; per layer the weights (out x in, row-major) then the bias";

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

/// The actor's head (policy.h): one logit per action, or one per level of each frequency.
enum class PolicyHead { kJoint, kFactored };

/// A freshly initialised E-Navi frequency policy: PolicyStateFeatureNames() inputs, the head's
/// outputs, orthogonal weights from `seed`.
PolicyFile MakeFrequencyPolicy(const ActionGrid& grid, std::uint64_t seed,
                               PolicyHead head = PolicyHead::kJoint,
                               const std::vector<int>& hidden = {150, 150});

/// The policy as a version 2 document with its weights packed at `precision`.
/// @throws std::logic_error when the parts disagree (feature count vs obs_dim, grid size vs
///   num_actions): a program bug, not bad input.
/// @throws std::domain_error naming the weight when one is not finite at `precision` (NaN, inf,
///   or beyond float32's range): such a network is not written.
nlohmann::json PolicyToJson(const PolicyFile& policy, WeightPrecision precision);
/// Reads version 2 (and version 1) documents.
/// @throws std::invalid_argument "<source>: <field>: <reason>" for a wrong format or version,
///   a missing field, a wrong shape, a weight block that is truncated, not base64, fails its
///   sha256 or holds a non-finite number, or inconsistent parts.
PolicyFile PolicyFromJson(const nlohmann::json& j, const std::string& source);

/// Writes a version 2 file with float32 weights, minified, atomically (temporary file + rename).
/// @throws std::runtime_error on I/O failure; std::domain_error as PolicyToJson (nothing is
///   written then, an existing file is kept).
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
/// The canonical bytes of a policy (minified version 2 JSON, float64 weights): what the farm
/// distributes and hashes, so the same network always has the same content hash.
std::string CanonicalPolicyText(const PolicyFile& policy);

}  // namespace enavi::navstack::rl
