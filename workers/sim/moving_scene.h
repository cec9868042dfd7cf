#pragma once
// A world with movers as the depth camera sees it, frame by frame (Embree types stay in
// embree_impl.h, as for EmbreeScene).

#include <memory>
#include <vector>

#include <Eigen/Geometry>

#include "workers/sim/embree_scene.h"
#include "worlds/mesh.h"

namespace enavi::sim {

/// One episode's Embree scenes of a world with movers: the world's static scene (shared and
/// untouched, so its BVH is built once per world) and a scene of the movers alone, their
/// triangles moved to the movers' poses by SetPoses and committed (a small BVH rebuilt per
/// frame). DepthCamera renders the static scene as it would without movers, then traces again
/// only the pixels whose rays can meet a mover (the image of the movers' bounding box): a frame
/// with no mover in view costs what the static world's does. Mutable: one episode, one thread;
/// SetPoses, then DepthCamera::Render.
class MovingScene {
 public:
  struct Impl;

  /// `mover_meshes`: each mover's shape in its own frame (worlds::MoverMesh).
  /// @throws std::invalid_argument for a bad mesh, std::runtime_error with Embree's message.
  MovingScene(std::shared_ptr<const EmbreeScene> world, const std::vector<worlds::TriangleMesh>& mover_meshes,
              const EmbreeDevice& device = EmbreeDevice::Get());
  ~MovingScene();
  MovingScene(const MovingScene&) = delete;
  MovingScene& operator=(const MovingScene&) = delete;

  /// Moves mover i's triangles to X_WM[i] and commits the scene.
  /// @pre X_WM.size() == the number of movers.
  void SetPoses(const std::vector<Eigen::Isometry3d>& X_WM);

  std::size_t mover_count() const;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::sim
