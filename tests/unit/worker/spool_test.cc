#include "workers/worker/spool.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;

api::ResultMessage Message(const std::string& episode, int attempt) {
  api::ResultMessage m;
  m.episode_id = episode;
  m.attempt = attempt;
  m.worker_id = "w1";
  m.job_id = "j1";
  m.wall_time_s = 1.25;
  m.result.spec.seed = 5;
  m.result.flight_time_s = 20;
  m.result.series.t = {0, 1};
  m.result.series.position = {{1, 2, 3}, {4, 5, 6}};
  return m;
}

class SpoolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("spool_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SpoolTest, SavedResultsSurviveAndLoadBackExactly) {
  {
    ResultSpool spool(dir_);
    spool.Save(Message("j1-00001", 1));
    spool.Save(Message("j1-00002", 2));
  }
  ResultSpool reopened(dir_);  // a restarted worker
  std::vector<std::string> problems;
  const auto loaded = reopened.LoadAll(&problems);
  EXPECT_TRUE(problems.empty());
  ASSERT_EQ(loaded.size(), 2u);
  EXPECT_EQ(loaded[0].episode_id, "j1-00001");
  EXPECT_EQ(loaded[1].attempt, 2);
  EXPECT_EQ(nlohmann::json(loaded[0].result).dump(), nlohmann::json(Message("j1-00001", 1).result).dump());
}

TEST_F(SpoolTest, RemovedResultIsGone) {
  ResultSpool spool(dir_);
  spool.Save(Message("j1-00001", 1));
  spool.Remove("j1-00001", 1);
  spool.Remove("j1-00001", 1);  // twice: harmless
  EXPECT_TRUE(spool.LoadAll(nullptr).empty());
}

TEST_F(SpoolTest, CorruptFileIsSetAsideAndReported) {
  ResultSpool spool(dir_);
  spool.Save(Message("j1-00001", 1));
  std::ofstream(dir_ / "j1-00009.1.result.json") << "{ truncated";
  std::vector<std::string> problems;
  const auto loaded = spool.LoadAll(&problems);
  EXPECT_EQ(loaded.size(), 1u);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("j1-00009.1.result.json"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "j1-00009.1.result.json.bad"));
}

TEST_F(SpoolTest, TemporaryOfAWriteCutOffByACrashIsRemovedAndReported) {
  // SIGKILL between the atomic write's open and its rename leaves NAME.result.json.tmp; a
  // restarted worker on the same spool must not keep it (nor anyone count it as unacknowledged).
  ResultSpool spool(dir_);
  spool.Save(Message("j1-00001", 1));
  std::ofstream(dir_ / "j1-00002.1.result.json.tmp") << "{ \"episode_id\": ";
  std::vector<std::string> problems;
  const auto loaded = spool.LoadAll(&problems);
  EXPECT_EQ(loaded.size(), 1u);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("interrupted write"), std::string::npos) << problems[0];
  EXPECT_FALSE(fs::exists(dir_ / "j1-00002.1.result.json.tmp"));
}

}  // namespace
}  // namespace enavi::worker
