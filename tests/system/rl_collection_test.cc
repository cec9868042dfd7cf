// RL data collection on the real farm processes with real E-Navi episodes (short `empty`
// worlds): a collection job survives a SIGKILLed worker and exports each episode exactly once;
// `enavi train --server` trains on the farm and writes a policy that `enavi fly` flies.
#include <set>

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
  ASSERT_TRUE(Eventually([&] { return client.Status(job.job_id).done >= 3; }, 120s));
  ASSERT_TRUE(Eventually([&] {
    for (const auto& w : client.Workers()) {
      if (w["worker_id"] == "w1" && !w["running"].empty()) return true;
    }
    return false;
  }, 60s));
  Process("w1").Signal(SIGKILL);
  ASSERT_TRUE(Eventually([&] { return client.Status(job.job_id).terminal(); }, 300s));
  ExpectExactlyOneResultPerEpisode(client, job.job_id, 20);
  int reruns = 0;
  for (const auto& e : client.Episodes(job.job_id)) reruns += e["attempts"].get<int>() > 1 ? 1 : 0;
  EXPECT_GE(reruns, 1) << "the killed worker's episode should have run again";

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
