#include "workers/sim/episode_provenance.h"

#include <cstring>

#include "api/provenance.h"
#include "navstack/rl/shipped_policy.h"
#include "navstack/runtime/cost_model.h"
#include "workers/sim/embree_scene.h"

namespace enavi::sim {

std::map<std::string, std::string> EpisodeProvenance(const api::EpisodeSpec& spec,
                                                     const board::BoardProfile& board,
                                                     const std::string& cost_family, bool uses_policy) {
  std::map<std::string, std::string> notes;
  const auto note = [&notes](const char* name) -> std::string& {
    return notes[std::string(api::kProvenanceNotePrefix) + name];
  };
  note("enavi_version") = api::BuildVersion();
  note("git_commit") = api::BuildCommit();
  if (uses_policy) {
    if (spec.policy.empty()) {
      const auto& files = navstack::rl::ShippedPolicyFiles();
      const auto it = files.find(navstack::rl::kShippedPolicyName);
      if (it != files.end()) note("policy_sha256") = api::Sha256Hex(it->second);
      note("policy") = std::string("shipped ") + navstack::rl::kShippedPolicyName;
    } else {
      note("policy_sha256") = api::Sha256File(spec.policy);
      note("policy") = spec.policy;
    }
  }
  if (cost_family.empty()) return notes;  // a stack of its own processes: measured, no cost model
  // The digest covers exactly what prices a job of this method on this board: its cost family's
  // reference ns per unit and per job divided by the board's per-core speed, and the rule that
  // applies them.
  const board::ReferenceCosts reference = board::LoadReferenceCosts();
  // A family not fitted yet flies on measured costs only (MakeEpisodeConfig): no prices to digest.
  if (!reference.families.contains(cost_family)) return notes;
  const auto coefficients = board::BoardCoefficients(board, reference, cost_family);
  std::string bytes(reinterpret_cast<const char*>(coefficients.ns_per_unit.data()),
                    sizeof(double) * coefficients.ns_per_unit.size());
  bytes.append(reinterpret_cast<const char*>(coefficients.ns_per_job.data()),
               sizeof(double) * coefficients.ns_per_job.size());
  bytes.append("revision " + std::to_string(navstack::kCostModelRevision));
  note("cost_model_sha256") = api::Sha256Hex(bytes).substr(0, 16);
  note("calibration_id") = reference.calibration_id;
  note("ray_kernels") = RayKernels();
  return notes;
}

}  // namespace enavi::sim
