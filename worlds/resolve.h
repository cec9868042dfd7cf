#pragma once
// One entry point from a user's --world argument to a World: a generator id, a world file, a
// bare mesh file (OBJ, glTF/GLB, DAE, STL, PLY, FBX) or a Gazebo SDF world with start and goal
// given separately. Part of enavi::world_import (it reads every format).

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "worlds/placement.h"
#include "worlds/world.h"

namespace enavi::worlds {

struct WorldRequest {
  std::string world;                          ///< a scenario id (Generators()), FILE.yaml, a mesh file or FILE.sdf/.world
  std::uint64_t seed = 1;                     ///< generator seed (ignored for files)
  std::map<std::string, std::string> params;  ///< generator parameters (--param k=v)
  std::optional<Eigen::Vector3d> start;       ///< required for mesh and SDF worlds, overrides otherwise
  std::optional<Eigen::Vector3d> goal;
  MeshPlacement placement;                    ///< mesh files only (--units, --scale, --up, --recenter)
  std::vector<std::filesystem::path> model_path;  ///< SDF worlds: where model:// URIs are looked up
};

/// Generates or loads and validates a world. Throws WorldError (a std::invalid_argument) naming
/// the file, field and reason on bad input.
World ResolveWorld(const WorldRequest& request);

}  // namespace enavi::worlds
