#pragma once
// One entry point from a user's --world argument to a World: a generator id, a world file, or a
// bare OBJ mesh with start and goal given separately.

#include <map>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "worlds/world.h"

namespace enavi::worlds {

struct WorldRequest {
  std::string world;                          ///< s1..s5, canyon, forest, empty, FILE.yaml or FILE.obj
  std::uint64_t seed = 1;                     ///< generator seed (ignored for files)
  std::map<std::string, std::string> params;  ///< generator parameters (--param k=v)
  std::optional<Eigen::Vector3d> start;       ///< required for .obj, overrides otherwise
  std::optional<Eigen::Vector3d> goal;
};

/// Generates or loads and validates a world. Throws WorldError (a std::invalid_argument) naming
/// the file, field and reason on bad input.
World ResolveWorld(const WorldRequest& request);

}  // namespace enavi::worlds
