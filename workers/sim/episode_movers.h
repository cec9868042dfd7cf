#pragma once
// A world's movers in an episode: where they are at each instant for the physics (kinematic
// bodies) and for the depth camera (MovingScene).

#include <memory>
#include <string>
#include <vector>

#include "workers/sim/embree_scene.h"
#include "workers/sim/moving_scene.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/static_world.h"
#include "worlds/movers.h"
#include "worlds/world.h"

namespace enavi::sim {

/// A world's movers, prepared once and shared read-only by the episodes flown in it: their
/// trajectories and their shapes as triangles (camera) and as collision shapes (physics), each
/// in the mover's own frame.
struct PreparedMovers {
  std::vector<std::string> names;
  std::vector<worlds::MoverTrajectory> trajectories;
  std::vector<worlds::TriangleMesh> meshes;
  std::vector<std::shared_ptr<const StaticCollisionWorld>> shapes;
};
/// Null for a world without movers.
std::shared_ptr<const PreparedMovers> PrepareMovers(const worlds::World& world);

/// One episode's movers on its sim clock. Deterministic: a pose is a function of the time only.
class EpisodeMovers {
 public:
  /// Adds each mover to `quad` as a kinematic body, posed at t = 0.
  EpisodeMovers(std::shared_ptr<const PreparedMovers> movers, std::shared_ptr<const EmbreeScene> world,
                QuadrotorSim* quad);

  /// Poses the kinematic bodies where the movers are at `t` (before quad->Step() from t).
  void PoseBodies(double t, QuadrotorSim* quad) const;
  /// The camera's scene with the movers where they are at `t`.
  const MovingScene& SceneAt(double t);
  /// What a contact's body (ContactEvent::body) is: "static" for the world, "mover:NAME".
  std::string Touched(int body) const;

 private:
  std::vector<Eigen::Isometry3d> PosesAt(double t) const;

  std::shared_ptr<const PreparedMovers> movers_;
  MovingScene scene_;
  std::vector<int> bodies_;  // QuadrotorSim's kinematic body of each mover
};

}  // namespace enavi::sim
