#pragma once
// What the flight controller tracks between two looks at a method (after each commit and each
// frame, under the lock commits take): the trajectory it follows, and that trajectory's
// predecessor until the new one starts (NavStack keeps following the old plan until then;
// Ego-Planner's plans start when they land), or a hold (emergency stop, fail-safe, scan, before
// the first plan). The emulated clock's navstack process publishes this to the simulator
// (workers/emulation/emulated_child.cc), our ROS node samples it for its PositionCommands
// (ros/node/): one rule for both.

#include <algorithm>
#include <memory>

#include "navstack/common/state.h"
#include "navstack/methods/navigator.h"
#include "navstack/planning/trajectory.h"

namespace enavi::navstack {

struct PublishedReference {
  std::shared_ptr<const Trajectory> current, previous;
  bool following = false;    ///< the method's reference is `current`'s (else: `hold`)
  TrajectorySample hold;     ///< the method's reference at the look

  TrajectorySample Sample(double t) const {
    if (!following || !current) return hold;
    if (t < current->start_time() && previous) return previous->Sample(t);
    return current->Sample(t);
  }
};

class ReferenceTracker {
 public:
  /// Looks at `nav` at sim time `now`; true when its trajectory changed since the last look.
  bool Update(const Navigator& nav, double now) {
    const std::shared_ptr<const Trajectory> traj = nav.trajectory();
    const bool changed = traj != ref_.current;
    // A new plan's predecessor is kept unless the method was holding.
    if (changed) {
      ref_.previous = ref_.following ? ref_.current : nullptr;
      ref_.current = traj;
    }
    // Holding shows as a reference that is not the trajectory's.
    ref_.following = false;
    if (traj) {
      const double t1 = std::max(now, traj->start_time());
      const double t2 = traj->end_time() + 1.0;
      ref_.following = Same(nav.Reference(t1), traj->Sample(t1)) && Same(nav.Reference(t2), traj->Sample(t2));
    }
    ref_.hold = nav.Reference(now);
    return changed;
  }
  const PublishedReference& reference() const { return ref_; }

 private:
  static bool Same(const TrajectorySample& a, const TrajectorySample& b) {
    return a.p == b.p && a.v == b.v && a.a == b.a && a.j == b.j && a.yaw == b.yaw && a.yaw_rate == b.yaw_rate;
  }
  PublishedReference ref_;
};

}  // namespace enavi::navstack
