#pragma once
// `learned`: a navigation policy trained by reinforcement learning (navstack/rl/nav_policy.h,
// docs/rl.md) flown as a method like any other. Each depth frame releases one inference job; the
// job reads the frame and the latest odometry when the board's scheduler starts it, costs the
// network's multiply-adds on the board (policy_flop, priced as the frequency adapter's network
// is: the navstack cost family's price per multiply-add over the board's per-core speed), and its
// velocity setpoint takes effect at the job's finish: the board's inference latency is in the
// loop. The controller tracks the setpoint as a reference moving at that velocity from where the
// vehicle was when it landed. `learned.zero_latency 1` is the ablation of simulators without a
// board: the inference is free and its action applies at the frame's instant.

#include "navstack/methods/method.h"

namespace enavi::navstack {

/// The method: one task (perception's slot; its CPU in results as task_cpu_util_pct.inference),
/// its policy file from the job's `policy` (a nav policy, rl::LoadNavPolicy), or its actions from
/// outside (MethodOptions::decisions: the Python environment, python/nav_env_core.h).
MethodInfo LearnedMethod();

}  // namespace enavi::navstack
