#pragma once
// The two methods built on NavStack: `enavi` (the Strategy Controller adapts rates and map
// resolution, paper Sec. V) and `fixed` (the same stack at the paper's fixed 30 Hz / 20 Hz /
// 0.1 m, no adaptation: the ablation that separates configuration from runtime).

#include "navstack/methods/method.h"

namespace enavi::navstack {

/// `fixed`: perception 30 Hz, planning on a 20 Hz timer, collision check after every map update,
/// no difference detection, 0.1 m map; the callbacks of one single-threaded ROS node, first come
/// first served without preemption (paper Sec. I, "partitioned scheme with static periods").
MethodInfo FixedMethod();
TaskRates FixedRates();

/// `enavi`: triggered planning, periodic collision and difference checks, the coarsest level of
/// the Resolution Adapter's ladder to start with, global EDF on all cores (paper Sec. III.A).
MethodInfo EnaviMethod();
TaskRates EnaviInitialRates();

}  // namespace enavi::navstack
