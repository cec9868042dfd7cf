#pragma once
// `enavi world convert`: any world the farm reads, written as the farm's own world file, so an
// imported world (a mesh with its placement, an SDF world) is reused byte-identically in job specs.

#include <filesystem>

#include "worlds/world.h"

namespace enavi::worlds {

/// Writes `world` to `out` (YAML, as SaveWorldFile). Mesh objects whose file lies under the
/// output's directory are referenced by a path relative to it, with their placement (units, up,
/// recenter, scale, yaw, position); `source_dir` is the directory their paths are relative to
/// (the input's). Any other mesh, and geometry with no file of its own (SDF), is written as an
/// OBJ in world coordinates (metres) under `<out stem>_meshes/` and referenced from there.
/// Throws std::runtime_error naming the path on a write failure.
void ConvertWorld(const World& world, const std::filesystem::path& source_dir, const std::filesystem::path& out);

}  // namespace enavi::worlds
