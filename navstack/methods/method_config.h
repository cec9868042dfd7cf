#pragma once
// A registered method configured for one flight: the method's options and scheduler, then
// overrides by tunable name, each checked against its range. The tunables are those the
// navigation stack itself reads (planner, perception, scheduler: StackTunables) and the method's
// own; `enavi fly --set`, job specs and our ROS node (ros/node/) name them alike. The camera's
// (decimation, noise) belong to the simulator that renders the frames (workers/sim).

#include <map>
#include <string>
#include <vector>

#include "navstack/methods/method.h"

namespace enavi::navstack {

struct MethodConfig {
  const MethodInfo* method = nullptr;
  MethodOptions nav;
  /// The method's scheduler, with the sched.* overrides applied (threads 0: all cores).
  MethodScheduler scheduler;
};

/// The stack's tunables every method accepts (planner.*, perception.*, sched.*).
const std::vector<MethodTunable>& StackTunables();
/// Every tunable `method` accepts here: StackTunables(), then the method's own.
std::vector<MethodTunable> StackTunablesFor(const MethodInfo& method);
/// "a, b, c": the names of `tunables`, for messages that list what is known.
std::string TunableNames(const std::vector<MethodTunable>& tunables);

/// `method` configured with `setup` (ConfigureMethod), no overrides yet.
MethodConfig ConfigureMethodDefaults(const MethodInfo& method, const MethodSetup& setup);
/// Sets the tunable `name` of `config`'s method to `value`; false when the method has no such
/// tunable (the caller says what is known). @throws std::invalid_argument "NAME: V is outside
/// [MIN, MAX]" (or "... or not an integer") for a value out of its range.
bool ApplyOverride(const std::string& name, double value, MethodConfig* config);

/// ConfigureMethodDefaults, then every override applied.
/// @throws std::invalid_argument "NAME: reason" for a name `method` does not have (listing those
/// it has) or a value outside its range.
MethodConfig ConfigureMethodWithOverrides(const MethodInfo& method, const MethodSetup& setup,
                                          const std::map<std::string, double>& overrides);

/// The range check of ApplyOverride, for tunables kept elsewhere (the simulator's camera.*).
void CheckTunableRange(const MethodTunable& tunable, double value);

}  // namespace enavi::navstack
