#pragma once
// World description: the static scene one episode flies through (worlds/generators.h and docs/results.md).
// Pure geometry: no Bullet, no Embree. Lengths in metres, angles in radians, z up.

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "worlds/mesh.h"

namespace enavi::worlds {

/// Bad world input (file, generator parameter, start/goal). The message is exactly
/// `FILE:LINE: FIELD: REASON`; without a known line `FILE: FIELD: REASON`, without a file
/// `FIELD: REASON`. FILE is the world/OBJ file as given, or the generator id.
class WorldError : public std::invalid_argument {
 public:
  WorldError(std::string file, int line, std::string field, std::string reason)
      : std::invalid_argument(Format(file, line, field, reason)),
        file_(std::move(file)), line_(line), field_(std::move(field)), reason_(std::move(reason)) {}

  const std::string& file() const { return file_; }
  int line() const { return line_; }  ///< 1-based; 0 when unknown
  const std::string& field() const { return field_; }
  const std::string& reason() const { return reason_; }

 private:
  static std::string Format(const std::string& file, int line, const std::string& field,
                            const std::string& reason) {
    std::string m;
    if (!file.empty()) {
      m.append(file);
      if (line > 0) m.append(":").append(std::to_string(line));
      m.append(": ");
    }
    m.append(field).append(": ").append(reason);
    return m;
  }
  std::string file_;
  int line_ = 0;
  std::string field_;
  std::string reason_;
};

/// Axis-aligned box rotated by `yaw` about its vertical centre axis.
struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Ones();  ///< full extents along the box's own x, y, z
  double yaw = 0.0;
};

/// Vertical cylinder standing on `base` (centre of its bottom disc).
struct Cylinder {
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  double radius = 0.5;
  double height = 1.0;
};

/// Ellipsoid (tree crowns, boulders); `radii` along world x, y, z.
struct Ellipsoid {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d radii = Eigen::Vector3d::Ones();
};

/// Up axis of a mesh file: y-up files (glTF, most DAE exports) are turned so their +y is world +z.
enum class UpAxis { kY, kZ };

/// Triangle mesh loaded from a file (OBJ, glTF/GLB, DAE, STL, PLY, FBX), placed by position, yaw
/// and uniform scale: p_W = position + Rz(yaw) * (scale * (offset + p_mesh)).
struct MeshObject {
  std::string path;  ///< as written in the world file (resolved relative to it); empty: geometry
                     ///< with no file of its own (an SDF primitive or a posed SDF mesh, world frame)
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0.0;
  double scale = 1.0;
  std::string units;          ///< the file's length unit as given; empty: the file's own, else metres
  std::optional<UpAxis> up;   ///< as given; nullopt: the file's own, else z
  bool recenter = false;      ///< as given: the mesh's anchor moves to `position`
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< m, the anchor (zero when recentred)
  TriangleMesh mesh;  ///< metres, z up, relative to the anchor (so floats keep their precision)
};

using Object = std::variant<Box, Cylinder, Ellipsoid, MeshObject>;

/// Ground: a horizontal plane at `z` over the world bounds, or none (e.g. indoors a box floor).
struct Ground {
  bool enabled = true;
  double z = 0.0;
};

struct WorldMetadata {
  std::string name;
  std::string scenario;  ///< generator id or "custom"
  std::uint64_t seed = 0;
  int generator_version = 0;
  std::map<std::string, std::string> params;  ///< generator parameters, sorted for stable output
  std::string import_note;  ///< what an importer left out (SDF lights, plugins, ...); not in world files
};

/// What a mover does after its last waypoint.
enum class MoverMode {
  kLoop,          ///< on to the first waypoint and round again
  kBackAndForth,  ///< back along its waypoints, and forth again
  kOnce,          ///< stays at the last waypoint
};

/// A point of a mover's path: where its frame's origin passes.
struct MoverWaypoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double t = 0.0;    ///< s after the mover starts (timed movers; speed movers: derived, not stored)
  double yaw = 0.0;  ///< rad about z (timed movers; speed movers face their direction of travel)
};

/// A moving obstacle (a person, a vehicle): a rigid shape whose frame follows waypoints, either
/// at a constant speed (its x axis along the direction of travel) or at given times with given
/// headings (Gazebo actors' scripted trajectories). Before `start_delay` it stands at the first
/// waypoint. Its pose at any time is worlds::MoverTrajectory's (worlds/movers.h).
struct Mover {
  std::string name;
  std::vector<Object> shape;  ///< in the mover's frame (x forward, z up; origin on the path)
  std::vector<MoverWaypoint> waypoints;  ///< at least two
  double speed = 0.0;         ///< m/s along the path; 0: timed by waypoints[i].t and .yaw
  MoverMode mode = MoverMode::kLoop;
  double start_delay = 0.0;   ///< s
};

/// A world: built once, shared read-only by every episode flown in it. Its objects are static;
/// its movers move on the episode's sim clock.
struct World {
  Eigen::AlignedBox3d bounds;  ///< flight volume; nothing outside it is simulated
  Ground ground;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  std::vector<Object> objects;
  std::vector<Mover> movers;
  WorldMetadata metadata;
};

}  // namespace enavi::worlds
