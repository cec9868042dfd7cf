#include "worlds/placement.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "worlds/number_text.h"
#include "worlds/obj_import.h"
#include "worlds/primitives.h"

namespace enavi::worlds {

std::optional<double> UnitMetres(std::string_view name) {
  for (const auto& u : kLengthUnits) {
    if (name == u.name) return u.metres;
  }
  return std::nullopt;
}

std::string UnitNames() {
  std::string out;
  for (const auto& u : kLengthUnits) out += (out.empty() ? "" : ", ") + std::string(u.name);
  return out;
}

std::optional<UpAxis> ParseUpAxis(std::string_view text) {
  if (text == "y") return UpAxis::kY;
  if (text == "z") return UpAxis::kZ;
  return std::nullopt;
}

const char* UpAxisName(UpAxis up) { return up == UpAxis::kY ? "y" : "z"; }

MeshPlacement ParsePlacement(const std::string& units, double scale, const std::string& up, bool recenter) {
  MeshPlacement p;
  if (!units.empty() && !UnitMetres(units)) {
    throw WorldError("", 0, "units", "unknown unit '" + units + "' (known: " + UnitNames() + ")");
  }
  p.units = units;
  if (!(scale > 0.0 && scale <= 1000.0)) {
    throw WorldError("", 0, "scale", "must be in (0, 1000] (got " + FormatFixed(scale, 6) + ")");
  }
  p.scale = scale;
  if (!up.empty()) {
    p.up = ParseUpAxis(up);
    if (!p.up) throw WorldError("", 0, "up", "expected y or z (got '" + up + "')");
  }
  p.recenter = recenter;
  return p;
}

Eigen::AlignedBox3d ImportedMesh::Bounds() const {
  Eigen::AlignedBox3d box;
  for (const auto& v : vertices) box.extend(v);
  return box;
}

MeshObject PlaceMesh(const ImportedMesh& mesh, const MeshPlacement& placement, std::string path,
                     const std::string& file) {
  MeshObject object;
  object.path = std::move(path);
  object.units = placement.units;
  object.up = placement.up;
  object.recenter = placement.recenter;
  object.scale = placement.scale;

  // Metres per stored unit: the declared unit wins, else the file's own, else metres.
  double unit = mesh.file_unit_m.value_or(1.0);
  if (!placement.units.empty()) {
    const auto declared = UnitMetres(placement.units);
    if (!declared) throw WorldError(file, 0, "units", "unknown unit '" + placement.units + "' (known: " + UnitNames() + ")");
    unit = *declared;
  }
  const double factor = unit / mesh.applied_unit_m;
  const UpAxis up = placement.up.value_or(mesh.file_up.value_or(UpAxis::kZ));

  // Upright metres in double: y-up turns +90 degrees about x, (x, y, z) -> (x, -z, y).
  std::vector<Eigen::Vector3d> upright;
  upright.reserve(mesh.vertices.size());
  Eigen::AlignedBox3d box;
  for (const auto& v : mesh.vertices) {
    const Eigen::Vector3d q = up == UpAxis::kY ? Eigen::Vector3d(factor * v.x(), -factor * v.z(), factor * v.y())
                                               : Eigen::Vector3d(factor * v.x(), factor * v.y(), factor * v.z());
    upright.push_back(q);
    box.extend(q);
  }
  const Eigen::Vector3d anchor = box.isEmpty() ? Eigen::Vector3d::Zero()
                                               : Eigen::Vector3d(0.5 * (box.min().x() + box.max().x()),
                                                                 0.5 * (box.min().y() + box.max().y()), box.min().z());
  object.offset = placement.recenter ? Eigen::Vector3d::Zero() : anchor;
  object.mesh.vertices.reserve(upright.size());
  for (const auto& q : upright) object.mesh.vertices.push_back((q - anchor).cast<float>());
  object.mesh.triangles = mesh.triangles;
  return object;
}

void CheckPlacedRange(const MeshObject& mesh, const std::string& file, int line, const std::string& field) {
  const Eigen::AlignedBox3d placed = ObjectBounds(mesh);
  const double reach = std::max(placed.min().cwiseAbs().maxCoeff(), placed.max().cwiseAbs().maxCoeff());
  if (reach <= kMaxCoordinate) return;
  // Which options would help: a unit when none was given, recentring when it is off.
  const double span = placed.sizes().maxCoeff();
  std::string hint;
  if (mesh.units.empty() && mesh.scale == 1.0) {
    hint = "if the file is not in metres, give its unit (--units " + UnitNames() + ") or --scale";
  }
  if (!mesh.recenter) hint += std::string(hint.empty() ? "" : "; ") + "--recenter moves it to the origin";
  throw WorldError(file, line, field,
                   "placed, the mesh reaches " + FormatFixed(reach, 1) + " m from the origin (limit +-100000 m; it spans " +
                       FormatFixed(span, 1) + " m)" + (hint.empty() ? "" : ": " + hint));
}

Eigen::AlignedBox3d PaddedBounds(const Eigen::AlignedBox3d& objects, const Eigen::Vector3d& start,
                                 const Eigen::Vector3d& goal, double padding, const std::string& file) {
  Eigen::AlignedBox3d bounds = objects;
  bounds.extend(start);
  bounds.extend(goal);
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(padding);
  bounds = Eigen::AlignedBox3d(bounds.min() - pad, bounds.max() + pad);
  const Eigen::Vector3d extent = bounds.sizes();
  if (extent.maxCoeff() > kMaxExtent) {
    throw WorldError(file, 0, "bounds",
                     "objects, start and goal span " + FormatFixed(extent.maxCoeff(), 1) +
                         " m (limit 2000 m per axis): check --units/--scale, or fly a part of the world");
  }
  return bounds;
}

World WorldFromMesh(const std::filesystem::path& path, const ImportedMesh& mesh, const MeshPlacement& placement,
                    const Eigen::Vector3d& start, const Eigen::Vector3d& goal, double padding) {
  MeshObject object = PlaceMesh(mesh, placement, path.filename().string(), path.string());
  CheckPlacedRange(object, path.string(), 0, "mesh");
  World world;
  world.bounds = PaddedBounds(ObjectBounds(object), start, goal, padding, path.string());
  world.ground.enabled = false;  // a mesh scene brings its own ground, if it has one
  world.start = start;
  world.goal = goal;
  world.objects.emplace_back(std::move(object));
  world.metadata.name = path.stem().string();
  world.metadata.scenario = "custom";
  return world;
}

}  // namespace enavi::worlds
