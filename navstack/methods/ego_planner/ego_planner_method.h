#pragma once
// `baseline`: the paper's baseline, Ego-Planner's node as it runs (ego_planner_node.h), with its
// mechanisms as tunables so that an ablation can switch each off.

#include "navstack/methods/method.h"

namespace enavi::navstack {

MethodInfo EgoPlannerMethod();

}  // namespace enavi::navstack
