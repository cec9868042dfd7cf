#include "server/store/ingest.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/queries.h"
#include "server/store/schema.h"
#include "server/store/series_codec.h"
#include "server/store/store.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <utility>

#include <gtest/gtest.h>

#include "server/store/sqlite.h"

namespace enavi::server {
namespace {

namespace fs = std::filesystem;

std::vector<api::EpisodeSpec> Episodes(int n) {
  std::vector<api::EpisodeSpec> out;
  for (int i = 0; i < n; ++i) {
    api::EpisodeSpec e;
    e.board = i % 2 == 0 ? "tx2" : "pi4b";
    e.world = "s1";
    e.method = "enavi";
    e.seed = static_cast<std::uint64_t>(i + 1);
    out.push_back(e);
  }
  return out;
}

api::ResultMessage Ok(const Lease& l, const std::string& worker) {
  api::ResultMessage m;
  m.episode_id = l.episode_id;
  m.attempt = l.attempt;
  m.worker_id = worker;
  m.job_id = l.job_id;
  m.status = api::ResultStatus::kOk;
  m.wall_time_s = 1.0;
  m.result.spec = l.spec;
  m.result.scenario = l.spec.world;
  m.result.success = true;
  m.result.flight_time_s = 12.5;
  m.result.path_length_m = 40.0;
  m.result.series.t = {0.0, 0.1};
  m.result.series.position = {{1, 2, 3}, {4, 5, 6}};
  m.result.series.eci = {0.1, 0.2};
  return m;
}

api::ResultMessage Err(const Lease& l, const std::string& worker, const std::string& why) {
  api::ResultMessage m;
  m.episode_id = l.episode_id;
  m.attempt = l.attempt;
  m.worker_id = worker;
  m.job_id = l.job_id;
  m.status = api::ResultStatus::kError;
  m.error = why;
  return m;
}

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("store_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    store_ = std::make_unique<Store>(db());
  }
  void TearDown() override {
    store_.reset();
    fs::remove_all(dir_);
  }
  fs::path db() const { return dir_ / "farm.db"; }
  void Reopen() {
    store_.reset();
    store_ = std::make_unique<Store>(db());
  }
  api::JobProgress Progress(const std::string& job) { return *store_->jobs().Progress(job, kNow); }

  static constexpr std::int64_t kNow = 1'000'000;
  static constexpr std::int64_t kLease = 15'000;
  fs::path dir_;
  std::unique_ptr<Store> store_;
};

TEST_F(StoreTest, NewJobHasAllEpisodesPending) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(5), kNow);
  const auto p = Progress(job);
  EXPECT_EQ(p.state, "running");
  EXPECT_EQ(p.total, 5);
  EXPECT_EQ(p.pending, 5);
  EXPECT_EQ(p.started_ms, 0) << "not started before the first lease";
  EXPECT_FALSE(store_->jobs().Progress("nope", kNow).has_value());
}

TEST_F(StoreTest, LeasingTakesOldestEpisodesInOrderAndCountsAttempts) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(5), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 2, {}, kNow + kLease, kNow);
  ASSERT_EQ(leases.size(), 2u);
  EXPECT_EQ(leases[0].episode_id, job + "-00000");
  EXPECT_EQ(leases[1].episode_id, job + "-00001");
  EXPECT_EQ(leases[0].attempt, 1);
  EXPECT_EQ(leases[1].spec.board, "pi4b");
  const auto p = Progress(job);
  EXPECT_EQ(p.leased, 2);
  EXPECT_EQ(p.pending, 3);
  EXPECT_EQ(p.started_ms, kNow);
  EXPECT_EQ(store_->leases().LeasedCounts().at("w1"), 2);
}

TEST_F(StoreTest, LeasingHonoursWorkerCapabilities) {
  store_->jobs().CreateJob("j", "yaml", Episodes(4), kNow);
  WorkerCapabilities caps;
  caps.boards = {"pi4b"};
  const auto leases = store_->leases().LeaseEpisodes("w1", 10, caps, kNow + kLease, kNow);
  ASSERT_EQ(leases.size(), 2u);
  for (const auto& l : leases) EXPECT_EQ(l.spec.board, "pi4b");
  caps.boards.clear();
  caps.clocks = {"emulated"};
  EXPECT_TRUE(store_->leases().LeaseEpisodes("w2", 10, caps, kNow + kLease, kNow).empty())
      << "every episode is virtual-clock";
}

TEST_F(StoreTest, ResultMakesEpisodeDoneAndJobFinishes) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(2), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 2, {}, kNow + kLease, kNow);
  const auto out = store_->ingest().Ingest({Ok(leases[0], "w1"), Ok(leases[1], "w1")}, kNow + 10);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].ack, api::AckStatus::kStored);
  EXPECT_EQ(out[0].event, "episode_done");
  const auto p = Progress(job);
  EXPECT_EQ(p.done, 2);
  EXPECT_EQ(p.state, "done");
  EXPECT_EQ(p.finished_ms, kNow + 10);
  const auto results = store_->queries().Results(job);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_EQ(results[0]["episode_id"], leases[0].episode_id);
  EXPECT_EQ(results[0]["board"], "tx2");
  EXPECT_EQ(results[0]["seed"], 1);
  EXPECT_EQ(results[0]["flight_time_s"], 12.5);
  EXPECT_FALSE(results[0].contains("series")) << "tables do not carry time series";
}

TEST_F(StoreTest, DuplicateResultIsAcknowledgedAndIgnored) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  auto first = Ok(leases[0], "w1");
  EXPECT_EQ(store_->ingest().Ingest({first}, kNow)[0].ack, api::AckStatus::kStored);
  auto again = first;
  again.result.flight_time_s = 99.0;  // a different payload must not replace the stored one
  const auto out = store_->ingest().Ingest({again, again}, kNow + 5);
  EXPECT_EQ(out[0].ack, api::AckStatus::kDuplicate);
  EXPECT_EQ(out[1].ack, api::AckStatus::kDuplicate);
  const auto results = store_->queries().Results(job);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0]["flight_time_s"], 12.5);
}

TEST_F(StoreTest, DuplicateWithinOneBatchIsStoredOnce) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  const auto out = store_->ingest().Ingest({Ok(leases[0], "w1"), Ok(leases[0], "w1")}, kNow);
  EXPECT_EQ(out[0].ack, api::AckStatus::kStored);
  EXPECT_EQ(out[1].ack, api::AckStatus::kDuplicate);
  EXPECT_EQ(store_->queries().Results(job).size(), 1u);
}

TEST_F(StoreTest, FullResultKeepsTimeSeriesAndEvents) {
  store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  auto m = Ok(leases[0], "w1");
  m.result.events = {{0.5, "replan", "x"}};
  store_->ingest().Ingest({m}, kNow);
  const auto full = store_->queries().FullResult(leases[0].episode_id);
  ASSERT_TRUE(full.has_value());
  EXPECT_EQ(full->series.t, m.result.series.t);
  EXPECT_EQ(full->series.position, m.result.series.position);
  EXPECT_EQ(full->series.eci, m.result.series.eci);
  ASSERT_EQ(full->events.size(), 1u);
  EXPECT_EQ(full->events[0].kind, "replan");
  EXPECT_EQ(full->spec.seed, 1u);
}

TEST_F(StoreTest, UnknownEpisodeResultIsAcknowledgedAsUnknown) {
  Lease ghost;
  ghost.episode_id = "jdead-00000";
  ghost.attempt = 1;
  EXPECT_EQ(store_->ingest().Ingest({Ok(ghost, "w1")}, kNow)[0].ack, api::AckStatus::kUnknown);
}

TEST_F(StoreTest, RogueResultsAreTheAttemptsErrorAndNeverStored) {
  // A worker's ok result with a NaN metric, for another board, or with a series column longer
  // than t: each attempt is recorded as failed with the reason; no result row appears.
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  const std::vector<std::pair<std::string, std::function<void(api::EpisodeResult*)>>> rogues = {
      {"flight_time_s: not a finite number", [](api::EpisodeResult* r) { r->flight_time_s = std::nan(""); }},
      {"spec.board: not this episode's", [](api::EpisodeResult* r) { r->spec.board = "x86"; }},
      {"series.eci: 3 samples, t has 2", [](api::EpisodeResult* r) { r->series.eci.push_back(0.3); }}};
  for (const auto& [reason, spoil] : rogues) {
    const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
    ASSERT_EQ(leases.size(), 1u) << reason;
    api::ResultMessage m = Ok(leases[0], "w1");
    spoil(&m.result);
    const auto out = store_->ingest().Ingest({m}, kNow);
    EXPECT_EQ(out[0].ack, api::AckStatus::kRecorded) << reason;
    EXPECT_NE(out[0].detail.find("result refused: " + reason), std::string::npos) << out[0].detail;
    EXPECT_NE(store_->jobs().Episodes(job)[0].last_error.find(reason), std::string::npos) << reason;
  }
  EXPECT_TRUE(store_->queries().Results(job).empty());
  EXPECT_EQ(Progress(job).failed, 1);
}

TEST_F(StoreTest, ExpiredLeaseGoesBackToPendingAndIsLeasedAgain) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  EXPECT_TRUE(store_->leases().ExpireLeases(kNow + kLease - 1).empty()) << "not expired yet";
  const auto released = store_->leases().ExpireLeases(kNow + kLease + 1);
  ASSERT_EQ(released.size(), 1u);
  EXPECT_FALSE(released[0].failed);
  EXPECT_EQ(released[0].worker, "w1");
  EXPECT_EQ(Progress(job).pending, 1);
  const auto again = store_->leases().LeaseEpisodes("w2", 1, {}, kNow + 2 * kLease, kNow + kLease + 2);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].attempt, 2);
}

TEST_F(StoreTest, RenewalKeepsOnlyTheListedLeasesOfThatWorker) {
  store_->jobs().CreateJob("j", "yaml", Episodes(2), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 2, {}, kNow + kLease, kNow);
  // w1 reports only the first as running; a stranger's report renews nothing.
  EXPECT_EQ(store_->leases().RenewLeases("w1", {{leases[0].episode_id, 1}}, kNow + 3 * kLease), 1);
  EXPECT_EQ(store_->leases().RenewLeases("w2", {{leases[1].episode_id, 1}}, kNow + 3 * kLease), 0);
  EXPECT_EQ(store_->leases().RenewLeases("w1", {{leases[1].episode_id, 7}}, kNow + 3 * kLease), 0)
      << "wrong attempt";
  const auto released = store_->leases().ExpireLeases(kNow + kLease + 1);
  ASSERT_EQ(released.size(), 1u);
  EXPECT_EQ(released[0].episode_id, leases[1].episode_id);
}

TEST_F(StoreTest, ErrorsRequeueUntilTheAttemptLimitThenFailWithTheReason) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
    ASSERT_EQ(leases.size(), 1u) << "attempt " << attempt;
    EXPECT_EQ(leases[0].attempt, attempt);
    const auto out = store_->ingest().Ingest({Err(leases[0], "w1", "segfault #" + std::to_string(attempt))}, kNow);
    EXPECT_EQ(out[0].ack, api::AckStatus::kRecorded);
    EXPECT_EQ(out[0].event, attempt < 3 ? "requeued" : "episode_failed");
  }
  EXPECT_TRUE(store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow).empty());
  const auto p = Progress(job);
  EXPECT_EQ(p.failed, 1);
  EXPECT_EQ(p.state, "done");
  ASSERT_EQ(p.errors.size(), 1u);
  EXPECT_NE(p.errors[0].find("segfault #3 (gave up after 3 attempts)"), std::string::npos)
      << p.errors[0];
}

TEST_F(StoreTest, LostLeasesCountAsAttempts) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  for (int attempt = 1; attempt <= 3; ++attempt) {
    store_->leases().LeaseEpisodes("w" + std::to_string(attempt), 1, {}, kNow + kLease, kNow);
    const auto released = store_->leases().ReleaseWorker("w" + std::to_string(attempt), "worker gone", kNow);
    ASSERT_EQ(released.size(), 1u);
    EXPECT_EQ(released[0].failed, attempt == 3);
  }
  EXPECT_EQ(Progress(job).failed, 1);
}

TEST_F(StoreTest, RejectionDoesNotCountAsAnAttempt) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  for (int i = 0; i < 5; ++i) {
    const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
    ASSERT_EQ(leases.size(), 1u);
    EXPECT_EQ(leases[0].attempt, 1) << "rejections must not use up attempts";
    auto m = Err(leases[0], "w1", "no free slot");
    m.status = api::ResultStatus::kRejected;
    EXPECT_EQ(store_->ingest().Ingest({m}, kNow)[0].ack, api::AckStatus::kRecorded);
  }
  EXPECT_EQ(Progress(job).pending, 1);
}

TEST_F(StoreTest, StaleErrorFromAnOldAttemptIsDiscarded) {
  store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  const auto first = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  store_->leases().ReleaseWorker("w1", "worker gone", kNow);
  const auto second = store_->leases().LeaseEpisodes("w2", 1, {}, kNow + kLease, kNow);
  // w1 was not dead after all; its error must not disturb w2's lease.
  EXPECT_EQ(store_->ingest().Ingest({Err(first[0], "w1", "late")}, kNow)[0].ack, api::AckStatus::kDiscarded);
  EXPECT_TRUE(store_->leases().HoldsLease(second[0].episode_id, 2, "w2"));
}

TEST_F(StoreTest, LateSuccessOfAnEarlierAttemptCompletesTheEpisode) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(1), kNow);
  const auto first = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  store_->leases().ReleaseWorker("w1", "worker gone", kNow);
  const auto second = store_->leases().LeaseEpisodes("w2", 1, {}, kNow + kLease, kNow);
  EXPECT_EQ(store_->ingest().Ingest({Ok(first[0], "w1")}, kNow)[0].ack, api::AckStatus::kStored);
  EXPECT_EQ(store_->ingest().Ingest({Ok(second[0], "w2")}, kNow)[0].ack, api::AckStatus::kDuplicate);
  EXPECT_EQ(Progress(job).done, 1);
  EXPECT_EQ(store_->queries().Results(job).size(), 1u);
}

TEST_F(StoreTest, CancelRevokesLeasesDropsPendingAndDiscardsLateResults) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(3), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow);
  const auto revoked = store_->jobs().CancelJob(job, kNow + 1);
  ASSERT_TRUE(revoked.has_value());
  ASSERT_EQ(revoked->size(), 1u);
  EXPECT_EQ((*revoked)[0].episode_id, leases[0].episode_id);
  const auto p = Progress(job);
  EXPECT_EQ(p.state, "cancelled");
  EXPECT_EQ(p.cancelled, 3);
  EXPECT_TRUE(store_->leases().LeaseEpisodes("w1", 5, {}, kNow + kLease, kNow).empty());
  EXPECT_EQ(store_->ingest().Ingest({Ok(leases[0], "w1")}, kNow)[0].ack, api::AckStatus::kDiscarded);
  EXPECT_FALSE(store_->jobs().CancelJob("jnope", kNow).has_value());
}

TEST_F(StoreTest, RestartResumesUnfinishedJobsAndRequeuesExpiredLeases) {
  const std::string job = store_->jobs().CreateJob("j", "yaml", Episodes(4), kNow);
  const auto leases = store_->leases().LeaseEpisodes("w1", 3, {}, kNow + kLease, kNow);
  store_->ingest().Ingest({Ok(leases[0], "w1")}, kNow);
  store_->leases().RenewLeases("w1", {{leases[1].episode_id, 1}}, kNow + 10 * kLease);
  Reopen();  // the server process died; the same file is opened again
  auto p = Progress(job);
  EXPECT_EQ(p.state, "running");
  EXPECT_EQ(p.done, 1);
  EXPECT_EQ(p.leased, 2);
  EXPECT_EQ(p.pending, 1);
  // At restart time the un-renewed lease has expired; the renewed one is still held.
  const auto released = store_->leases().ExpireLeases(kNow + 2 * kLease);
  ASSERT_EQ(released.size(), 1u);
  EXPECT_EQ(released[0].episode_id, leases[2].episode_id);
  EXPECT_TRUE(store_->leases().HoldsLease(leases[1].episode_id, 1, "w1"));
  p = Progress(job);
  EXPECT_EQ(p.pending, 2);
  EXPECT_EQ(store_->queries().Results(job).size(), 1u) << "nothing lost";
  // And the duplicate of the stored result is still recognised after the restart.
  EXPECT_EQ(store_->ingest().Ingest({Ok(leases[0], "w1")}, kNow)[0].ack, api::AckStatus::kDuplicate);
}

TEST_F(StoreTest, DatabaseIsInWalModeWithFullSync) {
  Database raw(db(), 1000);
  Statement& mode = raw.Prepare("PRAGMA journal_mode");
  ASSERT_TRUE(mode.Step());
  EXPECT_EQ(mode.Text(0), "wal");
  Statement& version = raw.Prepare("PRAGMA user_version");
  ASSERT_TRUE(version.Step());
  EXPECT_EQ(version.Int(0), kStoreSchemaVersion);
}

TEST_F(StoreTest, NewerSchemaVersionIsRefused) {
  store_.reset();
  {
    Database raw(db(), 1000);
    raw.Exec("PRAGMA user_version = 99");
  }
  EXPECT_THROW(Store s(db()), StoreError);
}

TEST(SeriesBlobTest, PackUnpackRoundTripsAndRejectsGarbage) {
  api::TimeSeries s;
  s.t = {0, 0.5};
  s.position = {{1, 2, 3}, {4, 5, 6}};
  s.velocity = {{0, 0, 0}, {1, 1, 1}};
  s.res = {0.1, 0.2};
  const auto back = UnpackSeries(PackSeries(s));
  EXPECT_EQ(back.t, s.t);
  EXPECT_EQ(back.position, s.position);
  EXPECT_EQ(back.velocity, s.velocity);
  EXPECT_EQ(back.res, s.res);
  EXPECT_TRUE(back.eci.empty());
  auto blob = PackSeries(s);
  blob.resize(blob.size() - 3);
  EXPECT_THROW(UnpackSeries(blob), std::invalid_argument);
  EXPECT_THROW(UnpackSeries({'x', 'y'}), std::invalid_argument);
}

TEST(SeriesCodecTest, WindAndOdometryColumnsRoundTripAndSeriesStoredBeforeThemStillRead) {
  api::TimeSeries s;
  s.t = {0.0, 0.1};
  s.wind_speed = {3.5, 4.25};
  s.odometry_error = {0.01, 0.02};
  const auto back = UnpackSeries(PackSeries(s));
  EXPECT_EQ(back.wind_speed, s.wind_speed);
  EXPECT_EQ(back.odometry_error, s.odometry_error);
  // A blob written before the two columns existed ends after utilisation: 8 bytes shorter.
  s.wind_speed.clear();
  s.odometry_error.clear();
  auto old = PackSeries(s);
  old.resize(old.size() - 8);
  const auto read = UnpackSeries(old);
  EXPECT_EQ(read.t, s.t);
  EXPECT_TRUE(read.wind_speed.empty());
  EXPECT_TRUE(read.odometry_error.empty());
  auto longer = PackSeries(s);
  longer.push_back(0);
  EXPECT_THROW(UnpackSeries(longer), std::invalid_argument) << "trailing bytes";
}

}  // namespace
}  // namespace enavi::server
