#pragma once
// A method as small as one can be, in a folder of its own as a new method is: it plans once from
// the start to the goal on an empty map and follows that plan (it flies into whatever is in the way).

#include "navstack/methods/method.h"

namespace enavi::navstack {

/// `straight_to_goal`: one planning job at 1 Hz whose first run plans the whole way on a free
/// grid; cost family "navstack" (the job runs our planner), its CPU in results as
/// task_cpu_util_pct.one_plan; one tunable of its own, unused.
MethodInfo StraightToGoalMethod();

}  // namespace enavi::navstack
