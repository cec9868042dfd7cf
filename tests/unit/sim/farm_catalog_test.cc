// The farm's catalog is the registries' contents (boards: the embedded profiles; scenarios: the
// generators; clocks: sim::Clocks(); methods: navstack's), and job validation and the episode
// runner read the same lists: every registered name is accepted, every other name is refused
// with the registered ones in the message.
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "api/job_spec.h"
#include "navstack/methods/method_config.h"
#include "workers/emulation/emulated_nav_link.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_config.h"

namespace enavi::sim {
namespace {

// The clocks beyond the built-in virtual one are registered by the composition root, as enavi's
// main does.
const bool kEmulatedLinkRegistered = (emulation::RegisterEmulatedLink(), true);

std::string YamlList(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "[" : ", ") + n;
  return out + "]";
}

api::JobSpecOptions Options() {
  api::JobSpecOptions o;
  o.catalog = FarmCatalog();
  return o;
}

TEST(FarmCatalogTest, AJobOfEveryRegisteredBoardScenarioAndMethodIsAcceptedOnEveryClock) {
  const api::Catalog c = FarmCatalog();
  ASSERT_FALSE(c.boards.empty());
  ASSERT_FALSE(c.scenarios.empty());
  EXPECT_EQ(c.clocks, (std::vector<std::string>{"virtual", "emulated"})) << "the built-in clock, then the registered";
  std::vector<std::string> methods;
  for (const api::MethodEntry& m : c.methods) methods.push_back(m.name);
  for (const std::string& clock : c.clocks) {
    const api::JobSpec job = api::ParseJobSpec("boards: " + YamlList(c.boards) + "\nscenarios: " + YamlList(c.scenarios) +
                                                   "\nmethods: " + YamlList(methods) + "\nseeds: 1\nclock: " + clock + "\n",
                                               "job.yaml", Options());
    EXPECT_EQ(job.clock, clock);
    EXPECT_EQ(api::ExpandJob(job).size(), c.boards.size() * c.scenarios.size() * methods.size());
  }
}

// The heading's limits are tunables of every method (an ablation: planner.yaw_accel_max=1000 is
// about Ego-Planner's traj_server, which has no acceleration limit).
TEST(FarmCatalogTest, TheHeadingLimitsAreTunablesThatReachThePlanner) {
  for (const char* method : {"baseline", "fixed", "enavi"}) {
    api::EpisodeSpec spec;
    spec.method = method;
    EXPECT_EQ(MakeEpisodeConfig(spec).nav.planner.yaw_accel_max, 3.0) << method;
    spec.overrides = {{"planner.yaw_rate_max", 3.14}, {"planner.yaw_accel_max", 1000.0}};
    const EpisodeConfig c = MakeEpisodeConfig(spec);
    EXPECT_EQ(c.nav.planner.yaw_rate_max, 3.14) << method;
    EXPECT_EQ(c.nav.planner.yaw_accel_max, 1000.0) << method;
  }
}

// The stack's tunables are navstack's (navstack/methods/method_config.h), the camera's the
// simulator's; a spec's overrides reach both, and a bad one is refused naming it under overrides.
TEST(FarmCatalogTest, OverridesReachTheStackAndTheCameraAndABadOneIsRefusedNamingIt) {
  std::vector<std::string> names;
  for (const Tunable& t : CommonTunables()) names.push_back(t.name);
  const std::vector<std::string> stack_and_camera = [] {
    std::vector<std::string> out;
    for (const navstack::MethodTunable& t : navstack::StackTunables()) out.push_back(t.name);
    out.push_back("camera.decimation");
    out.push_back("camera.noise_k");
    return out;
  }();
  EXPECT_EQ(names, stack_and_camera);

  api::EpisodeSpec spec;
  spec.method = "fixed";
  spec.overrides = {{"camera.decimation", 4}, {"camera.noise_k", 0.01}, {"planner.v_max", 1.5}, {"sched.threads", 2},
                    {"rates.f_per", 20}};
  const EpisodeConfig c = MakeEpisodeConfig(spec);
  EXPECT_EQ(c.nav.camera.width, 160);
  EXPECT_EQ(c.noise.k, 0.01);
  EXPECT_EQ(c.nav.planner.v_max, 1.5);
  EXPECT_EQ(c.scheduler.threads, 2);
  EXPECT_EQ(c.nav.params.at("rates.f_per"), 20.0);

  auto refusal = [&spec](const std::map<std::string, double>& overrides) {
    spec.overrides = overrides;
    try {
      MakeEpisodeConfig(spec);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal({{"camera.noise_k", 0.1}}), "overrides.camera.noise_k: 0.1 is outside [0, 0.05]");
  EXPECT_EQ(refusal({{"planner.v_max", 20}}), "overrides.planner.v_max: 20 is outside [0.2, 10]");
  const std::string unknown = refusal({{"ego.fsm_hz", 10}});
  EXPECT_EQ(unknown.rfind("overrides.ego.fsm_hz: unknown parameter for method fixed (known: planner.v_max", 0), 0u)
      << unknown;
  EXPECT_NE(unknown.find("camera.noise_k"), std::string::npos) << unknown;
}

TEST(FarmCatalogTest, UnknownNamesAreRefusedWithTheRegisteredOnes) {
  const api::Catalog c = FarmCatalog();
  auto error = [](const std::string& yaml) {
    try {
      api::ParseJobSpec(yaml, "job.yaml", Options());
    } catch (const api::JobSpecError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string board = error("boards: [c64]\nscenarios: [s1]\nmethods: [baseline]\nseeds: 1\n");
  for (const std::string& b : c.boards) EXPECT_NE(board.find(b), std::string::npos) << board;
  const std::string scenario = error("boards: [host]\nscenarios: [moon]\nmethods: [baseline]\nseeds: 1\n");
  for (const std::string& s : c.scenarios) EXPECT_NE(scenario.find(s), std::string::npos) << scenario;
  const std::string clock = error("boards: [host]\nscenarios: [s1]\nmethods: [baseline]\nseeds: 1\nclock: wall\n");
  for (const std::string& k : c.clocks) EXPECT_NE(clock.find(k), std::string::npos) << clock;
}

TEST(FarmCatalogTest, TheEpisodeRunnerRefusesAnUnregisteredClockNamingTheRegisteredOnes) {
  api::EpisodeSpec spec;
  spec.world = "empty";
  spec.world_params["length"] = "5";
  spec.clock = "wall";
  try {
    RunEpisode(spec);
    FAIL() << "an unknown clock flew";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("unknown clock 'wall'"), std::string::npos) << what;
    for (const ClockInfo& c : Clocks()) EXPECT_NE(what.find(c.name), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace enavi::sim
