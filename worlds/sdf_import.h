#pragma once
// Gazebo SDF worlds (.sdf, .world) read with libsdformat: the static models' geometry becomes
// the farm's objects. Part of enavi::world_import.

#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "worlds/world.h"

namespace enavi::worlds {

/// The first <world> of an SDF file as a World (metres, z up, as SDF is):
/// - every static model, nested and <include>d ones too, link by link: its collision geometry,
///   or its visual geometry when a link has no collision;
/// - box, cylinder, sphere, ellipsoid and plane geometry, and mesh geometry (any mesh format the
///   farm reads, with its <scale>), at their resolved poses. Boxes turned only about z and upright
///   cylinders stay primitives; anything else posed is stored as a triangle mesh in the world
///   frame. The first horizontal plane is the ground; other planes become finite quads;
/// - <include> of model://NAME resolved against `model_path`, then GAZEBO_MODEL_PATH; the
///   standard `sun` and `ground_plane` models are known without either;
/// - actors: their links' geometry (else their <skin> mesh, rigid in its bind pose) as a timed
///   mover following their <script> trajectories (world poses, yaw only; <loop>, <delay_start>;
///   without <auto_start> they stand still), or standing at their pose without a trajectory;
/// - lights, skeleton animations, plugins, physics settings and non-static models are left out,
///   listed in metadata.import_note.
/// Bounds: the geometry (but the ground; movers along their waypoints) with start and goal, padded
/// by 2 m, floor at the ground.
/// Throws WorldError naming the file: SDF errors with their line, a model:// not found, an
/// unsupported geometry (heightmap, capsule, polyline).
World LoadSdfWorld(const std::filesystem::path& path, const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                   const std::vector<std::filesystem::path>& model_path);

/// True for .sdf and .world files (any case).
bool IsSdfFile(const std::filesystem::path& path);

}  // namespace enavi::worlds
