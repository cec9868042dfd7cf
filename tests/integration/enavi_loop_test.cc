// E-Navi in the closed loop: the Strategy Controller's tasks run on the board, adapt the rates
// and the resolution, and the same episode twice gives the same result; policy files are checked.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "navstack/adapt/action_grid.h"
#include "navstack/methods/registry.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/rollout.h"
#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"

namespace enavi::integration {
namespace {

// A policy of this build (freshly initialised: what these tests check does not depend on training).
std::string WritePolicy(const TempDir& dir, std::uint64_t seed = 7) {
  const std::string path = (dir.path() / "policy.json").string();
  navstack::rl::SavePolicyFile(path, navstack::rl::MakeFrequencyPolicy(navstack::ActionGrid(), seed));
  return path;
}

api::EpisodeSpec EnaviSpec(const std::string& policy) {
  api::EpisodeSpec spec = Spec("s3", 1);
  spec.board = "tx2";
  spec.method = "enavi";
  spec.policy = policy;
  spec.timeout_s = 8.0;
  return spec;
}

// E-Navi with the shipped policy on tx2.
api::EpisodeSpec ShippedPolicyOnTx2(const std::string& world, std::uint64_t seed) {
  api::EpisodeSpec spec = Spec(world, seed);
  spec.board = "tx2";
  spec.method = "enavi";
  return spec;
}

TEST(EnaviLoopTest, StrategyTasksRunOnTheBoardAndAdaptTheConfiguration) {
  const TempDir dir;
  const api::EpisodeResult r = sim::RunEpisode(EnaviSpec(WritePolicy(dir)));
  ASSERT_FALSE(r.collided) << Describe(r);
  EXPECT_GT(r.adapter_time_ms_mean, 0.0) << "the adapter is a task with a board cost";
  EXPECT_GT(r.eci_time_ms_mean, 0.0);
  EXPECT_GT(r.replans, 0) << "triggered planning planned at least once";
  EXPECT_EQ(r.notes.at("scheduler"), "global EDF on 4 thread(s)");
  // The configuration moved: several distinct perception rates or resolutions over the flight.
  std::set<double> f_per(r.series.f_per.begin(), r.series.f_per.end());
  std::set<double> res(r.series.res.begin(), r.series.res.end());
  EXPECT_GT(f_per.size() + res.size(), 2u) << "rates or resolution adapted";
  EXPECT_EQ(*res.begin() >= 0.1 - 1e-9 && *res.rbegin() <= 0.5 + 1e-9, true) << "resolution stays on the ladder";
}

TEST(EnaviLoopTest, SameEpisodeTwiceIsIdentical) {
  const TempDir dir;
  const api::EpisodeSpec spec = EnaviSpec(WritePolicy(dir));
  const std::string a = nlohmann::json(sim::RunEpisode(spec)).dump();
  const std::string b = nlohmann::json(sim::RunEpisode(spec)).dump();
  EXPECT_EQ(a, b);
}

// A collection job's flight (rollout recorded: the critic also runs) is the flight the same spec
// flies without one, so training and evaluation see the stack as it is deployed. It was not: the
// critic's work was charged to the board's clock, and the canyon seed 2 tx2 evaluation flight of
// one policy collided on the farm and reached the goal in `enavi fly`.
TEST(EnaviLoopTest, RecordingARolloutDoesNotChangeTheFlight) {
  const TempDir dir;
  const api::EpisodeSpec spec = EnaviSpec(WritePolicy(dir));
  navstack::rl::Rollout rollout;
  sim::EpisodeOptions recording;
  recording.rollout = &rollout;
  const std::string recorded = nlohmann::json(sim::RunEpisode(spec, recording)).dump();
  const std::string plain = nlohmann::json(sim::RunEpisode(spec)).dump();
  EXPECT_FALSE(rollout.steps.empty());
  EXPECT_EQ(recorded, plain);
}

// A hovering vehicle whose plans keep failing turns on the spot, retrying, instead of hovering
// blind (the scan; NavStackTest covers that the first plan to land ends it). The flight that first
// needed it (the untrained network on s3 seed 2, pi4b, boxed in by a refined map's leftovers out
// of view) no longer gets boxed in since the cost families repriced the stack, and none of that
// network's flights on s3 and s2 (seeds 1-8, five boards) stopped; here the planner is starved
// instead: 40 RRT samples a search, too few for any way on from the start of s3.
TEST(EnaviLoopTest, AVehicleWhosePlansKeepFailingTurnsOnTheSpot) {
  navstack::MethodInfo starved = *navstack::FindMethod("fixed");
  starved.name = "fixed-starved-search";
  const auto make = starved.make;
  starved.make = [make](const navstack::MethodOptions& options, navstack::TaskExecutor* executor,
                        const navstack::VehicleState& initial) {
    navstack::MethodOptions o = options;
    o.planner.max_search_iterations = 40;
    return make(o, executor, initial);
  };
  if (navstack::FindMethod(starved.name) == nullptr) navstack::RegisterMethod(starved);
  api::EpisodeSpec spec = Spec("s3", 1);
  spec.board = "tx2";
  spec.method = starved.name;
  spec.timeout_s = 10.0;
  const api::EpisodeResult r = sim::RunEpisode(spec);
  EXPECT_FALSE(r.collided) << Describe(r);
  int scans = 0;
  for (const api::EpisodeEvent& e : r.events) scans += e.kind == "scan";
  EXPECT_GE(scans, 1) << "plans kept failing while it hovered: it turns. " << Describe(r);
  EXPECT_LT(r.path_length_m, 0.5) << "on the spot";
  EXPECT_FALSE(r.success);
}

// The boxed-in flight of a deployed policy: E-Navi with the shipped policy on s3 seed 445, tx2.
// After an emergency stop it used to hover where its map, refined from 0.5 m and kept fine, still
// held the coarse cells of a partition and two columns 7-9 m away, beyond the 5 m mapping range:
// they closed the only door, turning could not show them again, and without the map reset it
// turned for the rest of the flight (timed out at 71 s); with the reset it forgot them after one
// fruitless turn. Since refinement steps expire on their own it still stops there (12.8 s) and
// turns, but a plan lands within the turn and it reaches the goal at 27.4 s without the reset;
// none of tx2 s3 seeds 400-480 times out without it either. So the reset itself is covered by
// NavStackTest's scan tests, and this keeps the flight from getting stuck again.
TEST(EnaviLoopTest, TheFlightThatOnceGotBoxedInReachesTheGoal) {
  const api::EpisodeResult r = sim::RunEpisode(ShippedPolicyOnTx2("s3", 445));
  EXPECT_TRUE(r.success) << Describe(r);
  EXPECT_FALSE(r.collided) << Describe(r);
}

// The reaction constraint's speed limit in flight: E-Navi with the shipped policy on s3 seed 5,
// tx2, 3.2 s in, at 1.91 m/s among the hall's obstacles, with no rate quick enough to stop in
// time (constraint_fallback). The limit once bound only the next plan; now the plan being flown
// is replaced at once, and the plan made under the limit is replaced again once the limit is
// lifted, so the vehicle does not crawl on at it. Here a decision lifts it 0.4 s later: too short
// for the speed to show the braking clearly, so the braking to the limit is checked on the plan
// itself, in NavStackTest. (Seed 2, the flight first chosen, no longer meets the limit since the
// heading's rate is acceleration limited.)
TEST(EnaviLoopTest, ASpeedLimitReplacesThePlanAtOnceAndItsLiftingLetsTheVehicleSpeedUpAgain) {
  const api::EpisodeResult r = sim::RunEpisode(ShippedPolicyOnTx2("s3", 5));
  ASSERT_TRUE(r.success) << Describe(r);
  double t_fallback = -1, t_limited = -1, t_lifted = -1;
  for (const api::EpisodeEvent& e : r.events) {
    if (e.kind == "constraint_fallback" && t_fallback < 0) t_fallback = e.t;
    if (t_fallback < 0 || e.kind != "replan") continue;
    if (e.detail == "speed_limit" && t_limited < 0) t_limited = e.t;
    if (e.detail == "speed_limit_lifted") {
      t_lifted = e.t;
      break;
    }
  }
  ASSERT_GE(t_fallback, 0.0) << "this flight no longer meets the limit; pick another: " << Describe(r);
  // One planning job after the decision, not the next timer or trigger.
  EXPECT_GE(t_limited, t_fallback) << "the plan being flown was not replaced under the limit: " << Describe(r);
  EXPECT_LT(t_limited, t_fallback + 0.05) << Describe(r);
  ASSERT_GT(t_lifted, t_fallback) << "the plan made under the limit was never replaced: " << Describe(r);
  double v_at_fallback = 0, fastest_after = 0;
  for (std::size_t i = 0; i < r.series.size(); ++i) {
    const double t = r.series.t[i];
    const api::Vec3& v = r.series.velocity[i];
    const double speed = std::hypot(v[0], v[1], v[2]);
    if (t <= t_fallback) v_at_fallback = speed;
    if (t > t_lifted && t <= t_lifted + 2.0) fastest_after = std::max(fastest_after, speed);
  }
  EXPECT_GT(fastest_after, v_at_fallback - 0.1) << "back at its speed within 2 s of the lifting, not crawling at the limit";
}

// The least-load rule (strategy.least_load, an ablation) never asks the network: two different
// policies fly the same flight with it, and the policy itself flies another.
TEST(EnaviLoopTest, TheLeastLoadRuleFliesTheSameWhateverThePolicyAndRecordsNoRollout) {
  const TempDir a_dir, b_dir;
  api::EpisodeSpec a = EnaviSpec(WritePolicy(a_dir, 7));
  api::EpisodeSpec b = EnaviSpec(WritePolicy(b_dir, 8));
  const api::EpisodeResult policy_a = sim::RunEpisode(a);
  a.overrides["strategy.least_load"] = 1;
  b.overrides["strategy.least_load"] = 1;
  const api::EpisodeResult rule_a = sim::RunEpisode(a);
  const api::EpisodeResult rule_b = sim::RunEpisode(b);
  ASSERT_FALSE(rule_a.collided) << Describe(rule_a);
  EXPECT_EQ(rule_a.series.f_per, rule_b.series.f_per);
  EXPECT_EQ(rule_a.series.f_col, rule_b.series.f_col);
  EXPECT_EQ(rule_a.series.f_dif, rule_b.series.f_dif);
  EXPECT_EQ(rule_a.series.position, rule_b.series.position);
  EXPECT_EQ(rule_a.nav_cpu_util_pct, rule_b.nav_cpu_util_pct);
  EXPECT_NE(rule_a.series.f_dif, policy_a.series.f_dif) << "the policy chose otherwise";
  navstack::rl::Rollout rollout;
  sim::EpisodeOptions recording;
  recording.rollout = &rollout;
  try {
    sim::RunEpisode(a, recording);
    FAIL() << "a rollout recorded with the rule would train the policy on actions it did not take";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("strategy.least_load"), std::string::npos) << e.what();
  }
}

TEST(EnaviLoopTest, ExploringEpisodeRecordsARolloutWithRewards) {
  const TempDir dir;
  api::EpisodeSpec spec = EnaviSpec(WritePolicy(dir));
  spec.overrides["strategy.explore"] = 1;
  navstack::rl::Rollout rollout;
  sim::EpisodeOptions options;
  options.rollout = &rollout;
  const api::EpisodeResult r = sim::RunEpisode(spec, options);
  // 5 decisions per second over the flight.
  EXPECT_NEAR(static_cast<double>(rollout.steps.size()), 5.0 * r.sim_time_s, 3.0);
  ASSERT_FALSE(rollout.steps.empty());
  EXPECT_EQ(rollout.steps.back().done, r.success || r.collided);
  double sum = 0;
  for (const auto& s : rollout.steps) {
    EXPECT_EQ(s.obs.size(), 16);
    EXPECT_EQ(s.mask.at(static_cast<std::size_t>(s.action)), 1) << "only feasible actions are taken";
    sum += s.reward;
  }
  EXPECT_NE(sum, 0.0) << "rewards were assigned";
}

TEST(EnaviLoopTest, MissingOrCorruptPolicyIsAClearError) {
  const TempDir dir;
  api::EpisodeSpec spec = EnaviSpec((dir.path() / "nope.json").string());
  try {
    sim::RunEpisode(spec);
    FAIL() << "a missing policy must be an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nope.json"), std::string::npos) << e.what();
  }
  const std::string corrupt = (dir.path() / "corrupt.json").string();
  std::ofstream(corrupt) << "{\"format\": \"enavi-policy\", \"version\": 1, \"actor\": [1, 2";
  spec.policy = corrupt;
  try {
    sim::RunEpisode(spec);
    FAIL() << "a corrupt policy must be an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt.json"), std::string::npos) << e.what();
  }
  // The CLI turns it into exit code 2 with the file named.
  const CliRun run = Enavi(dir, "fly --world s3 --method enavi --policy " + corrupt + " --json");
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_NE(run.err.find("corrupt.json"), std::string::npos) << run.err;
}

TEST(EnaviTrainTest, TrainsCheckpointsAndResumes) {
  const TempDir dir;
  const std::string out = (dir.path() / "policy.json").string();
  const std::string common = "train --boards tx2 --scenarios s3 --episodes-per-iter 2 --workers 2 --seed 3 "
                             "--eval-every 1 --eval-seeds 1 --out " + out;
  const CliRun first = Enavi(dir, common + " --iterations 1");
  ASSERT_EQ(first.code, 0) << first.err;
  const auto work = dir.path() / "policy.json.train";
  EXPECT_TRUE(std::filesystem::exists(work / "checkpoint.json"));
  EXPECT_TRUE(std::filesystem::exists(work / "learning_curve.png"));
  EXPECT_NE(first.err.find("eval after 0 updates  1 flights"), std::string::npos) << first.err;
  EXPECT_NE(first.out.find("evaluation (greedy, 1 fixed worlds)"), std::string::npos) << first.out;
  const CliRun resumed = Enavi(dir, common + " --iterations 2 --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("iter 2/2"), std::string::npos) << "resumes at the second iteration: " << resumed.err;
  EXPECT_EQ(resumed.err.find("iter 1/2"), std::string::npos) << resumed.err;
  const std::string csv = ReadFile(work / "learning_curve.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3) << "header + 2 iterations:\n" << csv;
  // The evaluation curve: the untrained policy, after 1 update (not flown again on resume), after 2.
  EXPECT_EQ(resumed.err.find("eval after 1 updates"), std::string::npos) << resumed.err;
  EXPECT_NE(resumed.err.find("eval after 2 updates"), std::string::npos) << resumed.err;
  const std::string evals = ReadFile(work / "evaluation_curve.csv");
  ASSERT_EQ(std::count(evals.begin(), evals.end(), '\n'), 4) << "header + 3 evaluations:\n" << evals;
  for (const char* row : {"\n0,1,0,", "\n1,1,0,", "\n2,1,0,"}) EXPECT_NE(evals.find(row), std::string::npos) << evals;
  for (const char* p : {"policy_after_0.json", "policy_after_1.json", "policy_after_2.json"})
    EXPECT_TRUE(std::filesystem::exists(work / p)) << p;
  const std::string flights = ReadFile(work / "evaluations.jsonl");
  EXPECT_EQ(std::count(flights.begin(), flights.end(), '\n'), 3) << flights;
  // The trained policy flies.
  const CliRun fly = Enavi(dir, "fly --world s3 --board tx2 --method enavi --timeout 3 --json --policy " + out);
  EXPECT_EQ(fly.code, 0) << fly.err;
}

TEST(EnaviTrainTest, RefusesEvaluationSeedsTrainingDraws) {
  const TempDir dir;
  const CliRun run = Enavi(dir, "train --boards tx2 --scenarios s3 --eval-seeds 1,150 --out " +
                                    (dir.path() / "policy.json").string());
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_NE(run.err.find("--eval-seeds: seed 150 is a training seed"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "policy.json.train")) << "refused before anything is written";
}

}  // namespace
}  // namespace enavi::integration
