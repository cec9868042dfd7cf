#include "workers/worker/episode_runner.h"

#include <unistd.h>

#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Runs tests/system/fake_episode as the episode command.
class EpisodeRunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("episode_runner_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    run_.command = {std::string(ENAVI_BINARY_DIR) + "/tests/fake_episode"};
    run_.dir = dir_ / "ep";
    run_.env = {"ENAVI_ATTEMPT=1"};
    spec_.board = "tx2";
    spec_.method = "enavi";
    spec_.seed = 3;
  }
  void TearDown() override { fs::remove_all(dir_); }

  EpisodeOutcome Run() { return RunEpisode(spec_, run_, abort_); }

  fs::path dir_;
  EpisodeRun run_;
  api::EpisodeSpec spec_;
  std::atomic<bool> abort_{false};
};

TEST_F(EpisodeRunnerTest, SuccessfulEpisodeReturnsItsResult) {
  const EpisodeOutcome out = Run();
  ASSERT_EQ(out.kind, EpisodeOutcome::Kind::kResult) << out.error;
  EXPECT_EQ(out.result.spec.board, "tx2");
  EXPECT_EQ(out.result.spec.seed, 3u);
  EXPECT_EQ(out.result.notes.at("producer"), "fake_episode");
  EXPECT_EQ(out.result.series.size(), 50u);
  EXPECT_TRUE(fs::exists(run_.dir / "spec.json"));
}

TEST_F(EpisodeRunnerTest, CrashIsAnErrorNamingTheSignalAndStderr) {
  spec_.overrides["fake.crash_attempts"] = 1;
  const EpisodeOutcome out = Run();
  ASSERT_EQ(out.kind, EpisodeOutcome::Kind::kError);
  EXPECT_NE(out.error.find("killed by signal 6"), std::string::npos) << out.error;
  EXPECT_NE(out.error.find("crashing on attempt 1 as asked"), std::string::npos) << out.error;
}

TEST_F(EpisodeRunnerTest, NonZeroExitIsAnError) {
  spec_.overrides["fake.exit_code"] = 4;
  const EpisodeOutcome out = Run();
  ASSERT_EQ(out.kind, EpisodeOutcome::Kind::kError);
  EXPECT_EQ(out.error.rfind("episode command exit code 4", 0), 0u) << out.error;
}

TEST_F(EpisodeRunnerTest, UnreadableResultIsAnError) {
  spec_.overrides["fake.garbage"] = 1;
  const EpisodeOutcome out = Run();
  ASSERT_EQ(out.kind, EpisodeOutcome::Kind::kError);
  EXPECT_EQ(out.error.rfind("invalid result file", 0), 0u) << out.error;
}

TEST_F(EpisodeRunnerTest, HangingEpisodeIsKilledAtTheWallClockLimit) {
  spec_.overrides["fake.hang"] = 1;
  run_.limits.wall_timeout = 1s;
  const EpisodeOutcome out = Run();
  ASSERT_EQ(out.kind, EpisodeOutcome::Kind::kError);
  EXPECT_EQ(out.error.rfind("wall-clock timeout after 1 s", 0), 0u) << out.error;
}

TEST_F(EpisodeRunnerTest, AbortStopsTheEpisode) {
  spec_.overrides["fake.hang"] = 1;
  std::thread aborter([&] {
    std::this_thread::sleep_for(100ms);
    abort_ = true;
  });
  const EpisodeOutcome out = Run();
  aborter.join();
  EXPECT_EQ(out.kind, EpisodeOutcome::Kind::kAborted);
}

TEST_F(EpisodeRunnerTest, MissingCommandIsAnErrorNotACrash) {
  run_.command = {"/nonexistent/enavi"};
  const EpisodeOutcome out = Run();
  ASSERT_EQ(out.kind, EpisodeOutcome::Kind::kError);
  EXPECT_EQ(out.error.rfind("cannot start the episode", 0), 0u) << out.error;
}

}  // namespace
}  // namespace enavi::worker
