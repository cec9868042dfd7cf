#pragma once
// Wavefront OBJ import: the geometry (v, f) of a mesh, nothing else.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "worlds/placement.h"
#include "worlds/world.h"

namespace enavi::worlds {

/// Hard limits shared by world files and OBJ meshes (docs/farm.md: oversized input is bad
/// input, refused before it costs memory).
inline constexpr std::uintmax_t kMaxFileBytes = 256ull << 20;  ///< 256 MiB, checked before parsing
inline constexpr std::size_t kMaxTriangles = 5'000'000;        ///< in one world, all objects
inline constexpr double kMaxExtent = 2000.0;                   ///< m, per axis of the bounds
inline constexpr double kMaxCoordinate = 1e5;                  ///< m, any coordinate ("absurd")

/// Checks that `path` is a regular file within kMaxFileBytes and returns its size; errors are
/// WorldError(path, 0, "file", reason).
std::uintmax_t CheckInputFile(const std::filesystem::path& path);

/// Reads a world or OBJ file whole, after checking that it is a regular file within
/// kMaxFileBytes; errors are WorldError(path, 0, "file", reason).
std::string ReadInputFile(const std::filesystem::path& path);

/// Parses OBJ text. Reads `v x y z [w]` (also `v x y z r g b`) and `f` with `v`, `v/vt`,
/// `v//vn` or `v/vt/vn` corners, negative (relative) indices; polygons are fan-triangulated.
/// Ignores vt, vn, vp, usemtl, mtllib, o, g, s, l, p and comments. Coordinates stay in double
/// precision and the file's units (|x| <= kMaxFileCoordinate); placement checks the metres.
/// `file_name` is used in errors:
/// WorldError `FILE:LINE: f: vertex index 17 out of range (file has 12 vertices)`.
ImportedMesh ParseObj(std::string_view text, const std::string& file_name);

/// Reads and parses an OBJ file (size checked against kMaxFileBytes first). Errors name `path`
/// as given.
ImportedMesh LoadObjFile(const std::filesystem::path& path);

}  // namespace enavi::worlds
