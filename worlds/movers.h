#pragma once
// Moving obstacles (worlds::Mover, world.h): where a mover is at a given sim time, its shape as
// triangles in its own frame, and its track for plots. Pure geometry, deterministic: the pose
// at a time is computed with + - * / sqrt, fmod and detmath only, so the same world and time give
// the same pose bits on every machine.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "worlds/mesh.h"
#include "worlds/world.h"

namespace enavi::worlds {

/// The pose of a mover's frame: its origin and its heading as the cosine and sine of its yaw.
struct MoverPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double cos_yaw = 1.0, sin_yaw = 0.0;

  /// X_WM: the mover's frame in the world (rotation about z, then translation).
  Eigen::Isometry3d Transform() const;
  /// A point given in the mover's frame, in the world frame.
  Eigen::Vector3d ToWorld(const Eigen::Vector3d& p_M) const;
};

/// A mover's motion, prepared once: Pose(t) for any sim time t >= 0 of an episode.
///
/// Speed movers travel their waypoints' polyline at `speed` (a loop closes it back to the first
/// waypoint), heading along the segment they are on (along the previous one on a vertical
/// segment), and facing back on the way back. Timed movers pass waypoint i at waypoints[i].t,
/// moving linearly in between with the yaw turning the short way round (as Gazebo interpolates
/// an actor's trajectory); a loop starts over at the first waypoint after the last one's time.
/// Before start_delay and before the first waypoint's time a mover stands at its first waypoint.
class MoverTrajectory {
 public:
  /// @throws std::invalid_argument for fewer than two waypoints, a non-positive speed path
  /// length or non-increasing waypoint times (ParseWorld refuses these with their line first).
  explicit MoverTrajectory(const Mover& mover);

  MoverPose Pose(double t) const;
  /// s: one round of its motion after the delay (loop: around; back and forth: there and back;
  /// once: to the end).
  double period() const { return period_; }

 private:
  struct Knot {
    Eigen::Vector3d p;
    double t;
    double yaw;     // timed movers
    double c, s;    // heading on the segment that starts here (speed movers), or of yaw (timed)
  };
  MoverPose AtLeg(double u, bool back) const;  // u in [0, leg duration]

  std::vector<Knot> knots_;
  bool timed_ = false;
  MoverMode mode_ = MoverMode::kLoop;
  double delay_ = 0.0;
  double leg_ = 0.0;     // s along the knots, from the first to the last
  double period_ = 0.0;
};

/// The mover's shape as one triangle mesh in its own frame.
TriangleMesh MoverMesh(const Mover& mover);

/// The polyline a mover's origin travels (waypoints, closed for a speed loop), for plots.
std::vector<Eigen::Vector3d> MoverTrack(const Mover& mover);

/// "loop", "back_and_forth", "once"; and back (false for an unknown name).
const char* MoverModeName(MoverMode mode);
bool ParseMoverMode(const std::string& name, MoverMode* mode);

}  // namespace enavi::worlds
