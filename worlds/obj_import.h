#pragma once
// Wavefront OBJ import: the geometry (v, f) of a mesh, nothing else.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "worlds/mesh.h"
#include "worlds/world.h"

namespace enavi::worlds {

/// Hard limits shared by world files and OBJ meshes (DESIGN.md section 9: oversized input is bad
/// input, refused before it costs memory).
inline constexpr std::uintmax_t kMaxFileBytes = 256ull << 20;  ///< 256 MiB, checked before parsing
inline constexpr std::size_t kMaxTriangles = 5'000'000;        ///< in one world, all objects
inline constexpr double kMaxExtent = 2000.0;                   ///< m, per axis of the bounds
inline constexpr double kMaxCoordinate = 1e5;                  ///< m, any coordinate ("absurd")

/// Reads a world or OBJ file whole, after checking that it is a regular file within
/// kMaxFileBytes; errors are WorldError(path, 0, "file", reason).
std::string ReadInputFile(const std::filesystem::path& path);

/// Parses OBJ text. Reads `v x y z [w]` (also `v x y z r g b`) and `f` with `v`, `v/vt`,
/// `v//vn` or `v/vt/vn` corners, negative (relative) indices; polygons are fan-triangulated.
/// Ignores vt, vn, vp, usemtl, mtllib, o, g, s, l, p and comments. `file_name` is used in errors:
/// WorldError `FILE:LINE: f: vertex index 17 out of range (file has 12 vertices)`.
TriangleMesh ParseObj(std::string_view text, const std::string& file_name);

/// Reads and parses an OBJ file (size checked against kMaxFileBytes first). Errors name `path`
/// as given.
TriangleMesh LoadObjFile(const std::filesystem::path& path);

/// A world made of one OBJ mesh (`enavi --world chair.obj --start ... --goal ...`): bounds are
/// the mesh bounds padded by `padding` and grown to contain start and goal (plus padding), no
/// ground plane, scenario "custom". Not validated here (see ValidateWorld / ResolveWorld).
World WorldFromObj(const std::filesystem::path& path, const Eigen::Vector3d& start,
                   const Eigen::Vector3d& goal, double padding = 2.0);

}  // namespace enavi::worlds
