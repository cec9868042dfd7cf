// The contract every registered navigation method passes (STYLE.md rule 8, after OMPL's planner
// harness), flown through sim::RunEpisode, the code path of `enavi fly`: an empty world and a
// wall to fly round reach the goal without collision, bit-identically on the virtual clock,
// with the per-task CPU reported and the vehicle inside the flight bounds; a goal walled in on
// every side ends with a clear end_reason, not a hang. Plus the registry: a method registered
// at run time flies through the same path.
#include <algorithm>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "navstack/methods/registry.h"
#include "navstack/planning/planner.h"
#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_config.h"
#include "worlds/resolve.h"
#include "worlds/world_io.h"

namespace enavi::integration {
namespace {

// Top view; a 4 m wall across the straight line, open on both sides:
//
//   y  4 +---------------------------+
//        |            ##             |
//      0 | S          ##           G |
//        |            ##             |
//     -4 +---------------------------+
//       -8                           8  x
constexpr const char* kWall = R"(format: enavi-world/1
name: "wall"
metadata: {scenario: "custom", seed: 0, generator_version: 0, params: {}}
bounds: {min: [-8.0, -4.0, 0.0], max: [8.0, 4.0, 4.0]}
ground: {z: 0.0}
start: [-6.0, 0.0, 1.5]
goal: [6.0, 0.0, 1.5]
objects:
  - box: {center: [0.0, 0.0, 2.0], size: [0.6, 4.0, 4.0], yaw: 0.0}
)";

// The goal inside a closed room: no path exists (the world is loaded without validation).
constexpr const char* kWalledIn = R"(format: enavi-world/1
name: "walled-in"
metadata: {scenario: "custom", seed: 0, generator_version: 0, params: {}}
bounds: {min: [-8.0, -5.0, 0.0], max: [8.0, 5.0, 4.0]}
ground: {z: 0.0}
start: [-6.0, 0.0, 1.5]
goal: [4.0, 0.0, 1.5]
objects:
  - box: {center: [4.0, 0.0, 3.9], size: [4.4, 4.4, 0.2], yaw: 0.0}
  - box: {center: [1.9, 0.0, 2.0], size: [0.2, 4.4, 4.0], yaw: 0.0}
  - box: {center: [6.1, 0.0, 2.0], size: [0.2, 4.4, 4.0], yaw: 0.0}
  - box: {center: [4.0, 2.1, 2.0], size: [4.4, 0.2, 4.0], yaw: 0.0}
  - box: {center: [4.0, -2.1, 2.0], size: [4.4, 0.2, 4.0], yaw: 0.0}
)";

std::shared_ptr<const sim::PreparedWorld> Load(const TempDir& dir, const std::string& name, const char* text,
                                               bool validate = true) {
  const auto path = dir.Write(name, text);
  worlds::WorldFileOptions o;
  o.validate = validate;
  return sim::PrepareWorld(worlds::LoadWorldFile(path, o));
}

api::EpisodeSpec MethodSpec(const std::string& method, const std::string& world) {
  api::EpisodeSpec spec = Spec(world, 1);
  spec.method = method;
  spec.board = "tx2";
  return spec;
}

void ExpectGoalWithoutCollision(const api::EpisodeResult& r, const worlds::World& world) {
  EXPECT_TRUE(r.success) << Describe(r);
  EXPECT_EQ(r.end_reason, "goal_reached") << Describe(r);
  EXPECT_FALSE(r.collided) << Describe(r);
  EXPECT_GT(r.replans, 0) << Describe(r);
  // Per-task CPU: reported, and the navigation total is their sum.
  EXPECT_GT(r.nav_cpu_util_pct, 0.0) << Describe(r);
  EXPECT_NEAR(r.nav_cpu_util_pct, r.task_cpu_util_pct.Sum(), 1e-9);
  EXPECT_GT(r.task_cpu_util_pct.perception, 0.0) << Describe(r);
  // The vehicle never left the flight bounds.
  ASSERT_GT(r.series.size(), 10u);
  Eigen::AlignedBox3d bounds = world.bounds;
  bounds.min().array() -= 0.05;
  bounds.max().array() += 0.05;
  for (std::size_t i = 0; i < r.series.size(); ++i) {
    const auto& p = r.series.position[i];
    EXPECT_TRUE(bounds.contains(Eigen::Vector3d(p[0], p[1], p[2])))
        << "t " << r.series.t[i] << ": (" << p[0] << ", " << p[1] << ", " << p[2] << ") outside the bounds";
  }
}

class MethodContractTest : public ::testing::TestWithParam<std::string> {};

TEST_P(MethodContractTest, CrossesAnEmptyWorld) {
  api::EpisodeSpec spec = MethodSpec(GetParam(), "empty");
  spec.world_params = {{"length", "12"}};
  worlds::WorldRequest request;
  request.world = spec.world;
  request.seed = spec.seed;
  request.params = spec.world_params;
  const auto world = sim::PrepareWorld(worlds::ResolveWorld(request));
  ExpectGoalWithoutCollision(sim::RunEpisode(spec, *world), world->world);
}

TEST_P(MethodContractTest, FliesRoundAWallTheSameWayTwice) {
  const TempDir dir;
  const auto world = Load(dir, "wall.yaml", kWall);
  const api::EpisodeSpec spec = MethodSpec(GetParam(), (dir.path() / "wall.yaml").string());
  const api::EpisodeResult first = sim::RunEpisode(spec, *world);
  ExpectGoalWithoutCollision(first, world->world);
  EXPECT_GT(first.path_length_m, first.straight_line_m) << "went round the wall: " << Describe(first);
  const api::EpisodeResult second = sim::RunEpisode(spec, *world);
  EXPECT_EQ(nlohmann::json(first).dump(), nlohmann::json(second).dump()) << "virtual clock, same spec: not identical";
}

TEST_P(MethodContractTest, AGoalWithNoPathEndsWithAReasonNotAHang) {
  const TempDir dir;
  const auto world = Load(dir, "walled-in.yaml", kWalledIn, /*validate=*/false);
  api::EpisodeSpec spec = MethodSpec(GetParam(), (dir.path() / "walled-in.yaml").string());
  spec.timeout_s = 12.0;
  const api::EpisodeResult r = sim::RunEpisode(spec, *world);
  EXPECT_FALSE(r.success) << Describe(r);
  EXPECT_FALSE(r.collided) << Describe(r);
  EXPECT_TRUE(r.end_reason == "timeout" || r.end_reason == "failsafe") << Describe(r);
  EXPECT_LE(r.sim_time_s, spec.timeout_s + 0.01) << Describe(r);
}

std::vector<std::string> Registered() { return navstack::MethodNames(); }

INSTANTIATE_TEST_SUITE_P(EveryRegisteredMethod, MethodContractTest, ::testing::ValuesIn(Registered()),
                         [](const auto& info) { return info.param; });

// A small method: plans once from the start to the goal on an empty map and follows that.
class StraightToGoal final : public navstack::Navigator {
 public:
  StraightToGoal(const navstack::NavStackOptions& o, navstack::TaskExecutor* exec, const navstack::VehicleState& s0)
      : options_(o), exec_(exec), start_(s0) {
    exec_->Register(navstack::TaskId::kPlanning, [this] { return Plan(); });
    exec_->SetRate(navstack::TaskId::kPlanning, 1.0);
  }
  void OnFrame(navstack::DepthFramePtr) override {}
  void OnState(const navstack::VehicleState&) override {}
  navstack::TrajectorySample Reference(double t) const override {
    if (traj_) return traj_->Sample(t);
    navstack::TrajectorySample hold;
    hold.p = start_.p_WB;
    return hold;
  }
  std::vector<navstack::NavEvent> TakeEvents() override { return std::exchange(events_, {}); }
  navstack::TaskRates rates() const override { return {}; }
  double map_resolution() const override { return 0.1; }
  std::shared_ptr<const navstack::Trajectory> trajectory() const override { return traj_; }
  std::int64_t plan_failures() const override { return 0; }

 private:
  navstack::JobOutput Plan() {
    navstack::JobOutput out;
    if (traj_) return out;
    navstack::PlanRequest request;
    request.t_start = exec_->now();
    request.start.p = start_.p_WB;
    request.goal_W = options_.goal;
    request.flight_bounds_W = options_.flight_bounds;
    const double res = 0.5;
    const Eigen::Vector3i dims = (options_.flight_bounds.sizes() / res).array().ceil().cast<int>();
    request.grid = std::make_shared<const navstack::VoxelGrid>(options_.flight_bounds.min(), res, dims,
                                                                navstack::CellState::kFree);
    auto result = std::make_shared<navstack::PlanResult>(navstack::Plan(request, options_.planner));
    out.work = result->work;
    out.commit = [this, result] {
      if (!result->ok()) return;
      traj_ = result->trajectory;
      events_.push_back({exec_->now(), "replan", "start"});
    };
    return out;
  }
  navstack::NavStackOptions options_;
  navstack::TaskExecutor* exec_;
  navstack::VehicleState start_;
  std::shared_ptr<const navstack::Trajectory> traj_;
  std::vector<navstack::NavEvent> events_;
};

TEST(MethodRegistryTest, AMethodRegisteredAtRunTimeFliesThroughTheEpisodePath) {
  navstack::MethodInfo m;
  m.name = "straight_to_goal";
  m.summary = "one plan on an empty map (test)";
  m.scheduler = {navstack::SchedulingPolicy::kGlobalEdf, 0};
  m.tunables = {{"straight.unused", 0, 1, 0, true, "a tunable of its own"}};
  m.make = [](const navstack::NavStackOptions& o, navstack::TaskExecutor* e, const navstack::VehicleState& s) {
    return std::unique_ptr<navstack::Navigator>(std::make_unique<StraightToGoal>(o, e, s));
  };
  navstack::RegisterMethod(m);
  EXPECT_THROW(navstack::RegisterMethod(m), std::invalid_argument) << "a name registers once";

  // Every list reads the registry: names, the CLI's tunables, the job validation catalog.
  const auto names = navstack::MethodNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "straight_to_goal"), names.end());
  const api::Catalog catalog = sim::FarmCatalog();
  const api::MethodEntry* entry = catalog.Find("straight_to_goal");
  ASSERT_NE(entry, nullptr);
  EXPECT_TRUE(std::any_of(entry->tunables.begin(), entry->tunables.end(),
                          [](const api::TunableRange& t) { return t.name == "straight.unused"; }));

  api::EpisodeSpec spec = MethodSpec("straight_to_goal", "empty");
  spec.world_params = {{"length", "10"}};
  spec.overrides = {{"straight.unused", 1}};
  const api::EpisodeResult r = sim::RunEpisode(spec);
  EXPECT_TRUE(r.success) << Describe(r);
  EXPECT_EQ(r.replans, 1) << Describe(r);
  EXPECT_EQ(r.replans_by_trigger.at("start"), 1);
  EXPECT_GT(r.task_cpu_util_pct.planning, 0.0) << Describe(r);

  spec.overrides = {{"ego.emergency_stop", 0}};
  EXPECT_THROW(sim::RunEpisode(spec), std::invalid_argument) << "another method's tunable is refused";
}

TEST(MethodRegistryTest, RefusesBrokenRegistrations) {
  navstack::MethodInfo m;
  m.name = "";
  EXPECT_THROW(navstack::RegisterMethod(m), std::invalid_argument);
  m.name = "no_factory";
  EXPECT_THROW(navstack::RegisterMethod(m), std::invalid_argument);
  m.make = [](const navstack::NavStackOptions&, navstack::TaskExecutor*, const navstack::VehicleState&) {
    return std::unique_ptr<navstack::Navigator>();
  };
  m.tunables = {{"x.y", 0, 1, 2, false, "default outside its range"}};
  EXPECT_THROW(navstack::RegisterMethod(m), std::invalid_argument);
  EXPECT_EQ(navstack::FindMethod("no_factory"), nullptr);
}

}  // namespace
}  // namespace enavi::integration
