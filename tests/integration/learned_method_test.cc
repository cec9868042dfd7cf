// The `learned` method (navstack/methods/learned/): a nav policy file flown through the episode,
// its inference priced on the board, its action landing when the board finishes it.
#include <filesystem>
#include <fstream>
#include <tuple>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "navstack/methods/method_config.h"
#include "navstack/methods/registry.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/nav_rollout.h"
#include "navstack/runtime/virtual_executor.h"
#include "workers/board/board_profile.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_child.h"

namespace enavi::integration {
namespace {

std::string PolicyFile(const std::string& name, int width, int height) {
  const std::string path = (std::filesystem::path(::testing::TempDir()) / name).string();
  navstack::rl::SaveNavPolicy(path, navstack::rl::MakeNavPolicy(width, height, 3));
  return path;
}

api::EpisodeSpec LearnedSpec(const std::string& policy, const std::string& board) {
  api::EpisodeSpec spec;
  spec.world = "forest";
  spec.world_params = {{"density", "2"}, {"length", "20"}};
  spec.seed = 4;
  spec.board = board;
  spec.method = "learned";
  spec.policy = policy;
  spec.timeout_s = 8;
  return spec;
}

// The board time of one inference: the network's multiply-adds and the image's pixels at the
// navstack family's prices over the board's per-core speed.
double InferenceMs(const std::string& board, std::int64_t macs, std::int64_t pixels) {
  const auto c = board::BoardCoefficients(board::LoadBoard(board), board::LoadReferenceCosts(), "navstack");
  return (c.ns_per_job[static_cast<int>(navstack::TaskId::kPerception)] +
          macs * c.ns_per_unit[static_cast<int>(navstack::WorkUnit::kPolicyFlop)] +
          pixels * c.ns_per_unit[static_cast<int>(navstack::WorkUnit::kPixel)]) / 1e6;
}

TEST(LearnedMethodTest, APolicyFileFliesTwiceTheSameAndItsInferenceIsPricedOnTheBoard) {
  const std::string policy = PolicyFile("learned-64.json", 64, 48);
  const api::EpisodeResult a = sim::RunEpisode(LearnedSpec(policy, "pi4b"));
  const api::EpisodeResult b = sim::RunEpisode(LearnedSpec(policy, "pi4b"));
  nlohmann::json ja = a, jb = b;
  for (nlohmann::json* j : {&ja, &jb}) {
    j->erase("wall_time_s");
    j->erase("episode_id");
  }
  EXPECT_EQ(ja.dump(), jb.dump());
  EXPECT_EQ(a.notes.at("depth_stream"), "64x48") << "the stream at the network's size";
  ASSERT_TRUE(a.task_cpu_util_pct.contains("inference"));
  EXPECT_FALSE(a.task_cpu_util_pct.contains("perception"));
  // One inference per frame at 30 Hz, each its board time.
  const std::int64_t macs = navstack::rl::MakeNavPolicy(64, 48, 0).multiply_adds();
  const double ms = InferenceMs("pi4b", macs, 64 * 48);
  EXPECT_NEAR(a.task_cpu_util_pct.at("inference"), 30 * ms / 10, 0.01 * 30 * ms / 10);
  EXPECT_NE(a.notes.at("task.perception").find("mean job " + std::to_string(ms).substr(0, 5)), std::string::npos)
      << a.notes.at("task.perception") << " vs " << ms;
  EXPECT_EQ(a.notes.at("provenance.policy"), policy);

  api::EpisodeSpec x86 = LearnedSpec(policy, "x86");
  const api::EpisodeResult fast = sim::RunEpisode(x86);
  EXPECT_LT(fast.task_cpu_util_pct.at("inference"), a.task_cpu_util_pct.at("inference")) << "x86 is the faster core";
  x86.overrides = {{"learned.zero_latency", 1}};
  EXPECT_EQ(sim::RunEpisode(x86).task_cpu_util_pct.at("inference"), 0.0) << "the ablation's inference is free";
}

TEST(LearnedMethodTest, TheActionTakesEffectWhenTheBoardFinishesTheInference) {
  const std::string policy = PolicyFile("learned-latency.json", 64, 48);
  const navstack::MethodInfo* info = navstack::FindMethod("learned");
  ASSERT_NE(info, nullptr);
  navstack::MethodSetup setup;
  setup.nav_policy = std::make_shared<const navstack::rl::NavPolicyNet>(navstack::rl::LoadNavPolicy(policy));
  navstack::MethodConfig config = navstack::ConfigureMethodDefaults(*info, setup);
  config.nav.goal = {20, 0, 2};
  const board::BoardProfile pi4b = board::LoadBoard("pi4b");
  const navstack::WorkCountCostModel cost(board::BoardCoefficients(pi4b, board::LoadReferenceCosts(), "navstack"));
  navstack::VirtualExecutor exec(1, cost);
  navstack::VehicleState s0;
  s0.p_WB = {0, 0, 2};
  auto nav = info->make(config.nav, &exec, s0);
  auto frame = std::make_shared<navstack::DepthFrame>();
  frame->image = navstack::DepthImage(64, 48);  // open sky
  nav->OnFrame(frame);
  const double ms = InferenceMs("pi4b", navstack::rl::MakeNavPolicy(64, 48, 0).multiply_adds(), 64 * 48);
  ASSERT_GT(ms, 0.5);
  exec.AdvanceTo(0.9 * ms / 1e3);
  EXPECT_EQ(nav->Reference(1.0).p, s0.p_WB) << "still hovering while the board computes";
  exec.AdvanceTo(1.1 * ms / 1e3);
  EXPECT_NE(nav->Reference(1.0).p, s0.p_WB) << "the setpoint from the inference's finish";

  // A file for another image size than the stream's is refused, naming both.
  const std::string wide = PolicyFile("learned-wide.json", 60, 48);
  api::EpisodeSpec bad = LearnedSpec(wide, "pi4b");
  try {
    sim::RunEpisode(bad);
    ADD_FAILURE() << "a 60x48 network flew";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("60x48"), std::string::npos) << e.what();
  }
  bad.policy.clear();
  EXPECT_THROW(sim::RunEpisode(bad), std::invalid_argument) << "no policy file";
}

// Collection (a job with collect: rollouts and method learned): the worker's child draws each
// action from the file's Gaussian outside the flight, decision by decision, and records it. The
// flight is the method's own with learned.explore (the same draws at the same instants), and the
// rollout holds every inference with its reward.
TEST(LearnedMethodTest, ACollectionFlightIsTheMethodsOwnFlightAndRecordsEveryDecision) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "learned-collect";
  fs::create_directories(dir);
  navstack::rl::NavPolicyNet net = navstack::rl::MakeNavPolicy(64, 48, 3);
  net.set_log_std({-1, -1, -1, -1});
  const std::string policy = (dir / "sampled.json").string();
  navstack::rl::SaveNavPolicy(policy, net);

  auto collect = [&](bool explore, const std::string& name) {
    api::EpisodeSpec spec = LearnedSpec(policy, "pi4b");
    spec.overrides["learned.explore"] = explore ? 1 : 0;
    const sim::ChildFiles files{(dir / (name + ".spec.json")).string(), (dir / (name + ".result.json")).string(),
                                (dir / (name + ".rollout")).string()};
    std::ofstream(files.spec_file) << nlohmann::json(spec).dump();
    const api::EpisodeResult result = sim::RunEpisodeChild(files);
    std::ifstream in(files.rollout_file, std::ios::binary);
    const std::string blob((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return std::make_tuple(spec, result, blob);
  };
  const auto strip = [](const api::EpisodeResult& r) {
    nlohmann::json j = r;
    j.erase("wall_time_s");
    return j.dump();
  };
  for (const bool explore : {false, true}) {
    SCOPED_TRACE(explore ? "sampled" : "greedy");
    const auto [spec, result, blob] = collect(explore, explore ? "sampled" : "greedy");
    EXPECT_EQ(strip(result), strip(sim::RunEpisode(spec))) << "the method's own flight";
    EXPECT_EQ(std::get<2>(collect(explore, "again")), blob) << "the same rollout, byte for byte";

    const navstack::rl::NavRollout r = navstack::rl::DecodeNavRollout(blob, "test");
    EXPECT_EQ(r.width, 64);
    EXPECT_EQ(r.height, 48);
    // One decision per frame at 30 Hz until the end; a terminal only on a goal or a collision.
    EXPECT_NEAR(static_cast<double>(r.steps.size()), 30 * result.flight_time_s, 2.0);
    EXPECT_EQ(r.steps.back().done, result.success || result.collided);
    EXPECT_EQ(r.info.at("flight_time_s"), result.flight_time_s);
    // Greedy: the network's output on what it saw (the stored depth is within 7.7e-6 of it);
    // sampled: that plus the Gaussian's noise (sigma e^-1 per component).
    double deviation = 0;
    for (const auto& s : r.steps) {
      navstack::rl::NavObservation seen{{}, s.state};
      for (const std::uint16_t d : s.depth) seen.depth.push_back(navstack::rl::DepthValue(d));
      const Eigen::Vector4d z = (s.action - net.Forward(seen)) / std::exp(-1.0);
      const double dev = z.norm() * std::exp(-1.0);
      if (!explore) EXPECT_LT(dev, 1e-3);
      deviation += dev / static_cast<double>(r.steps.size());
      // The log-density of the draw: sum over components of -z^2/2 - log sigma - log(2 pi)/2.
      const double log_prob = -0.5 * z.squaredNorm() + 4 * (1.0 - 0.5 * std::log(2 * M_PI));
      EXPECT_NEAR(s.log_prob, explore ? log_prob : 0.0, 0.01);
    }
    if (explore) EXPECT_NEAR(deviation, std::exp(-1.0) * 1.88, 0.15) << "E|N(0, sigma^2 I_4)| = 1.88 sigma";
  }
  // Sampling needs the file's Gaussian: refused by name, before any flight.
  api::EpisodeSpec greedy_only = LearnedSpec(PolicyFile("learned-nostd.json", 64, 48), "pi4b");
  greedy_only.overrides["learned.explore"] = 1;
  try {
    sim::RunEpisode(greedy_only);
    ADD_FAILURE() << "sampled without a log_std";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("learned.explore: the policy file has no log_std"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace enavi::integration
