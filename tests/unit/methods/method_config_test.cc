// A registered method configured with overrides by tunable name (navstack/methods/method_config.h:
// what `enavi fly --set`, job specs and our ROS node share): each of the stack's tunables sets
// what it names, a method's own tunables land in its params, and an unknown name or a value out
// of range is refused naming it.
#include "navstack/methods/method_config.h"

#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "navstack/methods/registry.h"

namespace enavi::navstack {
namespace {

std::string Refusal(const std::string& method, const std::map<std::string, double>& overrides) {
  try {
    ConfigureMethodWithOverrides(*FindMethod(method), {}, overrides);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(MethodConfigTest, TheStackTunablesAreThePlannersPerceptionsAndSchedulersWithDefaultsInTheirRanges) {
  std::set<std::string> names;
  for (const MethodTunable& t : StackTunables()) {
    EXPECT_TRUE(t.name.rfind("planner.", 0) == 0 || t.name.rfind("perception.", 0) == 0 || t.name.rfind("sched.", 0) == 0)
        << t.name << ": the camera's belong to the simulator";
    EXPECT_LE(t.min, t.default_value) << t.name;
    EXPECT_LE(t.default_value, t.max) << t.name;
    EXPECT_TRUE(names.insert(t.name).second) << t.name << " twice";
  }
  EXPECT_TRUE(names.count("planner.v_max") && names.count("perception.stride") && names.count("sched.threads"));
}

TEST(MethodConfigTest, OverridesSetWhatTheyNameOnTopOfTheMethodsDefaults) {
  const MethodInfo& fixed = *FindMethod("fixed");
  MethodSetup setup;
  setup.seed = 7;
  const MethodConfig defaults = ConfigureMethodDefaults(fixed, setup);
  EXPECT_EQ(defaults.method, &fixed);
  EXPECT_EQ(defaults.scheduler.threads, fixed.scheduler.threads);
  EXPECT_EQ(defaults.scheduler.policy, fixed.scheduler.policy);
  EXPECT_EQ(defaults.nav.seed, 7u);

  const MethodConfig c = ConfigureMethodWithOverrides(
      fixed, setup,
      {{"planner.v_max", 1.5}, {"planner.optimizer", 1}, {"perception.stride", 4}, {"sched.threads", 2},
       {"sched.global_edf", 1}, {"rates.f_per", 20}});
  EXPECT_EQ(c.nav.planner.v_max, 1.5);
  EXPECT_EQ(c.nav.planner.optimizer, PlannerOptimizer::kRebound);
  EXPECT_EQ(c.nav.perception_stride.value_or(0), 4);
  EXPECT_EQ(c.scheduler.threads, 2);
  EXPECT_EQ(c.scheduler.policy, SchedulingPolicy::kGlobalEdf);
  EXPECT_EQ(c.nav.seed, 7u);
  EXPECT_EQ(c.nav.params.at("rates.f_per"), 20.0) << "fixed's own tunable";
  EXPECT_EQ(c.nav.params.at("rates.f_plan"), 20.0) << "its default";
  const MethodConfig fifo = ConfigureMethodWithOverrides(fixed, setup, {{"sched.global_edf", 0}, {"sched.threads", 0}});
  EXPECT_EQ(fifo.scheduler.policy, SchedulingPolicy::kFifoNonPreemptive);
  EXPECT_EQ(fifo.scheduler.threads, fixed.scheduler.threads) << "0: the method's own";

  // A method's own tunable goes into its params.
  const MethodInfo& baseline = *FindMethod("baseline");
  ASSERT_FALSE(baseline.tunables.empty());
  const MethodTunable& own = baseline.tunables.front();
  MethodConfig b = ConfigureMethodDefaults(baseline, setup);
  EXPECT_TRUE(ApplyOverride(own.name, own.max, &b));
  EXPECT_EQ(b.nav.params.at(own.name), own.max);
  EXPECT_FALSE(ApplyOverride("camera.decimation", 2, &b)) << "the simulator's";
}

TEST(MethodConfigTest, AnUnknownNameOrAValueOutOfRangeIsRefusedSayingWhy) {
  const std::string unknown = Refusal("fixed", {{"ego.fsm_hz", 10}});
  EXPECT_EQ(unknown.rfind("ego.fsm_hz: unknown parameter for method fixed (known: planner.v_max, ", 0), 0u) << unknown;
  EXPECT_EQ(Refusal("fixed", {{"planner.v_max", 20}}), "planner.v_max: 20 is outside [0.2, 10]");
  EXPECT_EQ(Refusal("fixed", {{"perception.stride", 2.5}}), "perception.stride: 2.5 is outside [1, 64] or not an integer");
  EXPECT_EQ(Refusal("fixed", {{"planner.a_max", std::nan("")}}).rfind("planner.a_max: nan is outside", 0), 0u);
  const MethodTunable& own = FindMethod("baseline")->tunables.front();
  EXPECT_EQ(Refusal("baseline", {{own.name, own.max + 1}}).rfind(own.name + ": ", 0), 0u);
  EXPECT_EQ(Refusal("baseline", {{own.name, own.min}}), "");
}

}  // namespace
}  // namespace enavi::navstack
