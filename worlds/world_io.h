#pragma once
// World files (YAML, format "enavi-world/1"): loader with precise errors and a deterministic
// writer.
//
//   format: enavi-world/1
//   name: "s1-seed1"
//   metadata: {scenario: "s1", seed: 1, generator_version: 1, params: {length: "44.0"}}
//   bounds: {min: [x, y, z], max: [x, y, z]}
//   ground: {z: 0.0}            # or: ground: none
//   start: [x, y, z]
//   goal: [x, y, z]
//   objects:
//     - box: {center: [x, y, z], size: [sx, sy, sz], yaw: 0.3}
//     - cylinder: {base: [x, y, z], radius: r, height: h}
//     - ellipsoid: {center: [x, y, z], radii: [rx, ry, rz]}
//     - mesh: {file: "chair.obj", position: [x, y, z], yaw: 0.0, scale: 1.0}
//     - mesh: {file: "block.glb", position: [0, 0, 0], units: "mm", up: "z", recenter: true}
//   movers:                     # optional: moving obstacles (worlds/movers.h)
//     - name: "walker-0"
//       mode: "back_and_forth"  # or loop (default), once
//       speed: 1.4              # m/s along the waypoints, heading along the path
//       start_delay: 2.0        # s standing at the first waypoint
//       shape:                  # objects as above, in the mover's frame (x forward, z up)
//         - cylinder: {base: [0, 0, 0], radius: 0.3, height: 1.8}
//       waypoints: [[x, y, z], [x, y, z]]
//     - name: "actor"           # without a speed: timed waypoints (Gazebo actors)
//       shape: [...]
//       waypoints: [{t: 0, position: [x, y, z], yaw: 0}, {t: 4, position: [x, y, z], yaw: 1.57}]
//
// A mesh's `units` (m, cm, mm, in, ft) and `up` (y, z) default to what the file declares (DAE,
// glTF, FBX), else metres and z; `recenter` puts its anchor (horizontal centre of the bounds,
// lowest point) at `position`; `scale` multiplies after the unit.
//
// Mesh paths are relative to the world file and must stay inside its directory tree.
// Limits: file <= 256 MiB, bounds <= 2 km per axis, <= kMaxObjects objects, <= 5 M triangles,
// every coordinate within +-100 km, sizes and radii in (0, 2000] m, scale in (0, 1000],
// |yaw| <= 2 pi; <= 1000 movers of <= 10000 waypoints, inside the bounds, speed in (0, 50] m/s,
// times and delays in [0, 86400] s, increasing along a mover's timed waypoints, names unique.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "worlds/obj_import.h"
#include "worlds/placement.h"
#include "worlds/validate.h"
#include "worlds/world.h"

namespace enavi::worlds {

inline constexpr std::string_view kWorldFormat = "enavi-world/1";
inline constexpr std::size_t kMaxObjects = 100'000;
inline constexpr int kWorldFileDecimals = 4;  ///< numbers are rounded to 0.1 mm, trailing zeros trimmed

struct WorldFileOptions {
  std::optional<Eigen::Vector3d> start;  ///< overrides the file's start (which may then be absent)
  std::optional<Eigen::Vector3d> goal;
  bool validate = true;                  ///< run ValidateWorld; failures throw WorldError
  ValidationOptions validation;
  std::size_t max_objects = kMaxObjects;      ///< limits (lower them to sandbox untrusted input)
  std::size_t max_triangles = kMaxTriangles;
  MeshLoader load_mesh;  ///< reads mesh files; empty: .obj only (ResolveWorld passes every format)
};

/// Loads a world file: size check, YAML parse, schema (unknown keys, types, ranges, limits),
/// mesh files, then (by default) ValidateWorld. Throws WorldError `FILE:LINE: FIELD: REASON`.
World LoadWorldFile(const std::filesystem::path& path, const WorldFileOptions& options = {});

/// Parses world YAML text. `file_name` names the source in errors; mesh paths are resolved
/// against `base_dir` (and must stay under it).
World ParseWorld(std::string_view yaml, const std::string& file_name, const std::filesystem::path& base_dir,
                 const WorldFileOptions& options = {});

/// The world as YAML text: fixed key order, numbers via std::to_chars rounded to
/// kWorldFileDecimals, -0 written as 0, strings double-quoted. The same World gives the same
/// bytes on every machine and locale.
std::string WorldToYaml(const World& world);

/// Writes WorldToYaml(world) to `path`; throws std::runtime_error naming the path on failure.
void SaveWorldFile(const World& world, const std::filesystem::path& path);

}  // namespace enavi::worlds
