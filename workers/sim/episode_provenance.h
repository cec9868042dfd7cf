#pragma once
// Provenance notes of one episode (`provenance.*` in EpisodeResult::notes): the enavi build, the
// policy file's sha256 (methods that fly a policy), the cost model's coefficient digest and the
// calibration id of its reference costs, and the one property of the host that changes a flight:
// the class of Embree's ray kernels (RayKernels). The same build gives the same notes (and the
// same result.json) on every host of one kernel class.

#include <map>
#include <string>

#include "api/episode.h"
#include "workers/board/board_profile.h"

namespace enavi::sim {

std::map<std::string, std::string> EpisodeProvenance(const api::EpisodeSpec& spec,
                                                     const board::BoardProfile& board,
                                                     const std::string& cost_family, bool uses_policy);

}  // namespace enavi::sim
