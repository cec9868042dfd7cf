#pragma once
// From a mesh file's coordinates to world metres: the file's length unit, its up axis and an
// optional recentring, applied in double precision before anything is stored as float, so a
// georeferenced model (offsets near 1,000 km, in millimetres) keeps sub-millimetre detail.

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "worlds/world.h"

namespace enavi::worlds {

struct LengthUnit {
  const char* name;
  double metres;  ///< metres per unit
};
/// Units a mesh file may be declared in (`--units`, `units:`); inch and foot are exact by definition.
inline constexpr std::array<LengthUnit, 5> kLengthUnits = {
    {{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"in", 0.0254}, {"ft", 0.3048}}};
/// Largest |coordinate| a mesh file may hold before placement, in its own units.
inline constexpr double kMaxFileCoordinate = 1e12;

/// Metres per unit of `name`; nullopt if it is not one of kLengthUnits.
std::optional<double> UnitMetres(std::string_view name);
/// "m, cm, mm, in, ft": for messages and CLI help.
std::string UnitNames();
/// "y" or "z"; nullopt otherwise.
std::optional<UpAxis> ParseUpAxis(std::string_view text);
const char* UpAxisName(UpAxis up);

/// A mesh as a reader produced it, before placement: double precision, the file's own axes.
struct ImportedMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
  double applied_unit_m = 1.0;        ///< metres per unit the reader already applied (Assimp applies DAE <unit>)
  std::optional<double> file_unit_m;  ///< the unit the file declares, if it declares one
  std::optional<UpAxis> file_up;      ///< the up axis the file declares (glTF: y by its spec)

  std::size_t triangle_count() const { return triangles.size(); }
  Eigen::AlignedBox3d Bounds() const;
};

/// Reads a mesh file; throws WorldError naming the file. World files and the resolver take one
/// of these, so the format libraries (Assimp) stay out of the core worlds library.
using MeshLoader = std::function<ImportedMesh(const std::filesystem::path&)>;

/// How the file is placed: as given by the user (empty/nullopt: the file's own, else m and z).
struct MeshPlacement {
  std::string units;
  std::optional<UpAxis> up;
  bool recenter = false;  ///< horizontal centre of the bounds to x = y = 0, lowest point to z = 0
  double scale = 1.0;     ///< extra uniform factor (`--scale`), after units
};

/// A placement from its text form (CLI flags, job specs): `units` empty or one of kLengthUnits,
/// `up` empty, "y" or "z", `scale` in (0, 1000]. Throws WorldError(FIELD: REASON) otherwise.
MeshPlacement ParsePlacement(const std::string& units, double scale, const std::string& up, bool recenter);

/// A MeshObject at the origin (no yaw) from an imported mesh: units and up axis resolved,
/// vertices turned z-up, converted to metres and stored relative to the mesh's anchor (the
/// horizontal centre and lowest point of its bounds); `offset` puts it back unless recentred.
/// `path` is stored as given. Throws WorldError(file, "units", ...) on an unknown unit.
MeshObject PlaceMesh(const ImportedMesh& mesh, const MeshPlacement& placement, std::string path,
                     const std::string& file);

/// Refuses a placed mesh that reaches beyond +-kMaxCoordinate, saying which option would help
/// (--units, --scale, --recenter). `field` names the object ("mesh", "objects[3]").
void CheckPlacedRange(const MeshObject& mesh, const std::string& file, int line, const std::string& field);

/// A world made of one mesh file (`enavi fly --world block.glb --start ... --goal ...`): bounds
/// are the placed mesh's, grown to hold start and goal, padded by `padding`; no ground plane,
/// scenario "custom". Not validated here.
World WorldFromMesh(const std::filesystem::path& path, const ImportedMesh& mesh, const MeshPlacement& placement,
                    const Eigen::Vector3d& start, const Eigen::Vector3d& goal, double padding = 2.0);

/// Bounds of a set of objects grown to hold start and goal and padded; throws WorldError(file,
/// "bounds", ...) past kMaxExtent per axis. Shared by the mesh and SDF importers.
Eigen::AlignedBox3d PaddedBounds(const Eigen::AlignedBox3d& objects, const Eigen::Vector3d& start,
                                 const Eigen::Vector3d& goal, double padding, const std::string& file);

}  // namespace enavi::worlds
