// RL data collection on the real farm processes with real E-Navi episodes (short `empty`
// worlds): a collection job survives a SIGKILLed worker and exports each episode exactly once;
// `enavi train --server` trains on the farm and writes a policy that `enavi fly` flies. The same
// for the learned method's depth-image rollouts.
#include <fstream>
#include <set>

#include "navstack/rl/nav_policy.h"
#include "navstack/rl/nav_rollout.h"
#include "tests/system/farm_harness.h"

namespace enavi::testing {
namespace {

fs::path PolicyFile() { return fs::path(ENAVI_SOURCE_DIR) / "navstack/rl/policies/enavi_default.json"; }

class RlCollectionTest : public FarmFixture {
 protected:
  std::string RealEpisodes() const { return EnaviBinary().string() + " episode"; }

  // Runs a command to its end; returns its exit status.
  worker::ExitStatus Run(const std::string& name, std::vector<std::string> argv,
                         std::chrono::seconds timeout) {
    worker::ChildProcess& p = Start(name, std::move(argv));
    auto status = p.Wait(timeout);
    if (!status) {
      p.Signal(SIGKILL);
      ADD_FAILURE() << name << " did not finish within " << timeout.count() << " s";
      return *p.Wait(5s);
    }
    return *status;
  }

  // Waits until `done` episodes of the job are done and `worker` flies one, SIGKILLs it, waits for
  // the job's end and checks that every episode has one result and that the killed one ran again.
  void KillInAnEpisodeAndFinish(api::FarmClient& client, const std::string& job, int episodes, int done,
                                const std::string& worker) {
    ASSERT_TRUE(Eventually([&] { return client.Status(job).done >= done; }, 120s));
    ASSERT_TRUE(Eventually([&] {
      for (const auto& w : client.Workers()) {
        if (w["worker_id"] == worker && !w["running"].empty()) return true;
      }
      return false;
    }, 60s));
    Process(worker).Signal(SIGKILL);
    ASSERT_TRUE(Eventually([&] { return client.Status(job).terminal(); }, 300s));
    ExpectExactlyOneResultPerEpisode(client, job, episodes);
    int reruns = 0;
    for (const auto& e : client.Episodes(job)) reruns += e["attempts"].get<int>() > 1 ? 1 : 0;
    EXPECT_GE(reruns, 1) << "the killed worker's episode should have run again";
  }

  static bool NumpyAvailable() {
    return std::system("/usr/bin/python3 -c 'import numpy' > /dev/null 2>&1") == 0;
  }
};

TEST_F(RlCollectionTest, TwentyEpisodesSurviveAKilledWorkerAndExportExactlyOnce) {
  const std::string url = StartServer();
  StartWorker("w1", 1, 0, RealEpisodes());
  StartWorker("w2", 1, 0, RealEpisodes());
  api::FarmClient client(url);
  const std::string policy = client.UploadPolicy(ReadText(PolicyFile()));
  const auto job = client.Submit("name: collect\nboards: [tx2]\nscenarios: [empty]\nmethods: [enavi]\n"
                                 "seeds: 20\ncollect: rollouts\nsample: true\npolicy: \"" + policy + "\"\n",
                                 "collect.yaml");
  ASSERT_EQ(job.episodes, 20);

  // Kill w1 in the middle of an episode: its lease is lost and the episode runs again on w2.
  KillInAnEpisodeAndFinish(client, job.job_id, 20, 3, "w1");
  if (HasFatalFailure()) return;

  // Exactly one rollout per episode, each of the job's policy.
  const auto rollouts = client.Rollouts(job.job_id);
  ASSERT_EQ(rollouts.size(), 20u);
  std::set<std::string> ids;
  for (const auto& r : rollouts) {
    ids.insert(r.episode_id);
    EXPECT_EQ("sha256:" + r.policy_hash, policy);
  }
  EXPECT_EQ(ids.size(), 20u);

  const fs::path out = dir_ / "dataset";
  const auto exported = Run("export", {EnaviBinary().string(), "dataset", "export", job.job_id, "--out",
                                       out.string(), "--server", url, "--shard-steps", "500"}, 60s);
  ASSERT_TRUE(exported.ok()) << ReadText(dir_ / "export.log");
  const nlohmann::json schema = nlohmann::json::parse(ReadText(out / "schema.json"));
  EXPECT_EQ(schema["episodes"], 20);
  EXPECT_GE(schema["shards"].size(), 2u) << "500-step shards: several";

  if (!NumpyAvailable()) GTEST_SKIP() << "/usr/bin/python3 has no numpy (scripts/install-deps.sh installs it)";
  const auto loaded = Run("numpy", {"/usr/bin/python3", (fs::path(ENAVI_SOURCE_DIR) / "examples/load_dataset.py").string(),
                                    out.string(), "--episodes", "20"}, 60s);
  EXPECT_TRUE(loaded.ok()) << ReadText(dir_ / "numpy.log");
}

// The learned method's collection: depth images and velocity commands from a nav policy's
// Gaussian, through the same kill and the same exactly-once export.
TEST_F(RlCollectionTest, NavRolloutsSurviveAKilledWorkerAndExportAsImages) {
  // Each real episode starts after a second, so the kill below lands inside one (a 6 s forest
  // flight takes ~0.2 s of CPU).
  const fs::path slow = dir_ / "slow-episode.sh";
  std::ofstream(slow) << "#!/bin/sh\nsleep 1\nexec " << EnaviBinary().string() << " episode \"$@\"\n";
  fs::permissions(slow, fs::perms::owner_all);
  const std::string url = StartServer();
  StartWorker("w1", 1, 0, slow.string());
  StartWorker("w2", 1, 0, slow.string());
  api::FarmClient client(url);
  navstack::rl::NavPolicyNet net = navstack::rl::MakeNavPolicy(64, 48, 5);
  net.set_log_std({-1, -1, -1, -1});
  const std::string policy = client.UploadPolicy(navstack::rl::NavPolicyToJson(net).dump());
  const auto job = client.Submit("name: nav\nboards: [pi4b]\nscenarios: [forest]\nmethods: [learned]\nseeds: 8\n"
                                 "timeout_s: 6\nworld_params: {density: \"2\", length: \"20\"}\n"
                                 "collect: rollouts\nsample: true\npolicy: \"" + policy + "\"\n",
                                 "nav.yaml");
  ASSERT_EQ(job.episodes, 8);
  KillInAnEpisodeAndFinish(client, job.job_id, 8, 2, "w1");
  if (HasFatalFailure()) return;

  const auto rollouts = client.Rollouts(job.job_id);
  ASSERT_EQ(rollouts.size(), 8u);
  for (const auto& r : rollouts) {
    const navstack::rl::NavRollout nav = navstack::rl::DecodeNavRollout(r.rollout, r.episode_id);
    EXPECT_EQ(nav.width, 64);
    EXPECT_NEAR(static_cast<double>(nav.steps.size()), 30 * r.flight_time_s, 2.0) << r.episode_id;
    EXPECT_EQ("sha256:" + r.policy_hash, policy);
  }

  const fs::path out = dir_ / "nav-dataset";
  const auto exported = Run("export", {EnaviBinary().string(), "dataset", "export", job.job_id, "--out",
                                       out.string(), "--server", url, "--shard-steps", "300"}, 60s);
  ASSERT_TRUE(exported.ok()) << ReadText(dir_ / "export.log");
  const nlohmann::json schema = nlohmann::json::parse(ReadText(out / "schema.json"));
  EXPECT_EQ(schema["kind"], "nav");
  EXPECT_EQ(schema["episodes"], 8);
  EXPECT_GE(schema["shards"].size(), 2u) << "300-step shards: several";

  if (!NumpyAvailable()) GTEST_SKIP() << "/usr/bin/python3 has no numpy (scripts/install-deps.sh installs it)";
  const auto loaded = Run("numpy", {"/usr/bin/python3", (fs::path(ENAVI_SOURCE_DIR) / "examples/load_dataset.py").string(),
                                    out.string(), "--episodes", "8"}, 60s);
  EXPECT_TRUE(loaded.ok()) << ReadText(dir_ / "numpy.log");
}

TEST_F(RlCollectionTest, TrainOnTheFarmWritesAPolicyThatFlies) {
  const std::string url = StartServer();
  StartWorker("w1", 1, 0, RealEpisodes());
  StartWorker("w2", 1, 0, RealEpisodes());
  const fs::path policy = dir_ / "policy.json";
  const auto trained = Run("train", {EnaviBinary().string(), "train", "--server", url, "--iterations", "3",
                                     "--episodes-per-iter", "2", "--boards", "tx2", "--scenarios", "empty",
                                     "--out", policy.string()}, 300s);
  ASSERT_TRUE(trained.ok()) << ReadText(dir_ / "train.log");
  const std::string curve = ReadText(dir_ / "policy.json.train/learning_curve.csv");
  EXPECT_NE(curve.find("\n2,2,0,"), std::string::npos) << curve;  // iteration 2, 2 episodes, none failed

  const fs::path result = dir_ / "flight.json";
  const auto flown = Run("fly", {EnaviBinary().string(), "fly", "--world", "empty", "--board", "tx2",
                                 "--method", "enavi", "--policy", policy.string(), "--json"}, 120s);
  ASSERT_TRUE(flown.ok()) << ReadText(dir_ / "fly.log");
  EXPECT_NE(ReadText(dir_ / "fly.log").find("\"end_reason\""), std::string::npos);
}

}  // namespace
}  // namespace enavi::testing
