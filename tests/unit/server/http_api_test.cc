#include "workers/sim/episode_config.h"
#include "server/http/http_api.h"

#include <unistd.h>

#include <filesystem>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "server/store/jobs.h"
#include "api/client.h"
#include "tests/unit/api/farm_test_util.h"

namespace enavi::server {
namespace {

namespace fs = std::filesystem;

constexpr const char* kJob = R"(name: http-test
boards: [tx2]
scenarios: [s1]
methods: [baseline, enavi]
seeds: 2
)";

// A farm server (no workers) behind its HTTP API on an ephemeral loopback port.
class HttpApiTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("http_api_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    store_ = std::make_unique<Store>(dir_ / "farm.db");
    FarmServerOptions options;
    options.bus = testing::TestBus();
    farm_ = std::make_unique<FarmServer>(store_.get(), options);
    farm_->Start();
  }
  void TearDown() override {
    api_.reset();
    farm_.reset();
    store_.reset();
    fs::remove_all(dir_);
  }
  std::string Serve(const std::string& token = "", HttpOptions http = {}) {
    http.token = token;
    http.job_spec.allowed_roots = {dir_};
    http.job_spec.catalog = sim::FarmCatalog();
    api_ = std::make_unique<HttpApi>(farm_.get(), http);
    api_->Start();
    return api_->url();
  }

  fs::path dir_;
  std::unique_ptr<Store> store_;
  std::unique_ptr<FarmServer> farm_;
  std::unique_ptr<HttpApi> api_;
};

TEST_F(HttpApiTest, HandleRawServesOneRequestWithoutASocket) {
  HttpOptions http;
  http.job_spec.catalog = sim::FarmCatalog();
  HttpApi api(farm_.get(), http);  // never started: no port, no thread
  const std::string ok = api.HandleRaw("GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_EQ(ok.rfind("HTTP/1.1 200", 0), 0u) << ok;
  EXPECT_NE(ok.find("\"ok\":true"), std::string::npos) << ok;
  // The access checks apply as on a connection: a foreign Host on loopback is DNS rebinding.
  const std::string refused = api.HandleRaw("GET /api/health HTTP/1.1\r\nHost: evil.example\r\n\r\n");
  EXPECT_EQ(refused.rfind("HTTP/1.1 403", 0), 0u) << refused;
}

TEST_F(HttpApiTest, SubmitStatusEpisodesAndCancelRoundTrip) {
  api::FarmClient client(Serve());
  EXPECT_EQ(client.Health()["ok"], true);
  const auto submitted = client.Submit(kJob, "my-job.yaml");
  EXPECT_EQ(submitted.name, "http-test");
  EXPECT_EQ(submitted.episodes, 4);
  const api::JobProgress p = client.Status(submitted.job_id);
  EXPECT_EQ(p.total, 4);
  EXPECT_EQ(p.state, "running");
  const auto jobs = client.Jobs();
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].id, submitted.job_id);
  const auto episodes = client.Episodes(submitted.job_id);
  ASSERT_EQ(episodes.size(), 4u);
  EXPECT_EQ(episodes[1]["seed"], 2);
  EXPECT_TRUE(client.Results(submitted.job_id).empty());
  const api::JobProgress cancelled = client.Cancel(submitted.job_id);
  EXPECT_EQ(cancelled.state, "cancelled");
  EXPECT_EQ(cancelled.cancelled, 4);
}

TEST_F(HttpApiTest, BadSpecIsRejectedWithFileLineFieldAndNothingIsStored) {
  api::FarmClient client(Serve());
  try {
    client.Submit("boards: [tx2]\nscenarios: [s1]\nmethods: [warp]\nseeds: 1\n", "bad.yaml");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.yaml:3: methods: unknown method 'warp'", 0), 0u)
        << e.what();
  }
  EXPECT_TRUE(client.Jobs().empty()) << "a rejected job must change nothing";
}

TEST_F(HttpApiTest, UnknownJobIsBadInput) {
  api::FarmClient client(Serve());
  try {
    client.Status("jdoesnotexist");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "no job 'jdoesnotexist'");
  }
}

// The dashboard's compare mode and trend metric come from the address: bad values are 400s that
// name the parameter.
TEST_F(HttpApiTest, BadCompareModeAndTrendMetricAreRefusedNamingTheParameter) {
  api::FarmClient client(Serve());
  const std::string job = client.Submit(std::string(kJob) + "labels: {suite: nightly}\n", "job.yaml").job_id;
  auto get = [&](const std::string& target) {
    return api_->HandleRaw("GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  };
  const std::string mode = get("/api/compare?base=" + job + "&candidate=" + job + "&mode=bogus");
  EXPECT_EQ(mode.rfind("HTTP/1.1 400", 0), 0u) << mode;
  EXPECT_NE(mode.find("mode: 'bogus': expected auto, exact or paired"), std::string::npos) << mode;
  const std::string paired = get("/api/compare?base=" + job + "&candidate=" + job + "&mode=paired");
  EXPECT_EQ(paired.rfind("HTTP/1.1 200", 0), 0u) << paired;
  const std::string metric = get("/api/trend?label=suite=nightly&metric=x%27y");
  EXPECT_EQ(metric.rfind("HTTP/1.1 400", 0), 0u) << metric;
  EXPECT_NE(metric.find("metric: 'x'y'"), std::string::npos) << metric;
  const std::string trend = get("/api/trend?label=suite=nightly&metric=flight_time_s");
  EXPECT_EQ(trend.rfind("HTTP/1.1 200", 0), 0u) << trend;
  EXPECT_NE(trend.find("\"points\":[]"), std::string::npos) << trend;  // no results yet
}

// The compare view's data says how the two jobs' specs differ (from the episodes' specs, which
// the episode list carries) and what the mode could decide.
TEST_F(HttpApiTest, CompareListsHowTheJobsSpecsDiffer) {
  api::FarmClient client(Serve());
  const std::string base = client.Submit(std::string(kJob) + "labels: {run: fast}\n", "a.yaml").job_id;
  const std::string candidate =
      client.Submit(std::string(kJob) + "labels: {run: slow}\noverrides: {planner.v_max: 1.0}\n", "b.yaml").job_id;
  EXPECT_EQ(client.Episodes(candidate)[0]["spec"]["overrides"]["planner.v_max"], 1.0);
  const std::string reply =
      api_->HandleRaw("GET /api/compare?base=" + base + "&candidate=" + candidate + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  ASSERT_EQ(reply.rfind("HTTP/1.1 200", 0), 0u) << reply;
  const nlohmann::json j = nlohmann::json::parse(reply.substr(reply.find("\r\n\r\n") + 4));
  EXPECT_EQ(j["verdict"], "no_change") << "no results yet";
  EXPECT_TRUE(j["specs_compared"]);
  ASSERT_EQ(j["spec_changes"].size(), 2u) << j["spec_changes"].dump();
  EXPECT_EQ(j["spec_changes"][1]["name"], "label.run");
  EXPECT_EQ(j["spec_changes"][1]["base_values"][0], "fast");
}

TEST_F(HttpApiTest, TokenIsRequiredForStateChangesOnly) {
  const std::string url = Serve("s3cret");
  api::FarmClient anonymous(url);
  EXPECT_NO_THROW(anonymous.Jobs()) << "reading needs no token";
  try {
    anonymous.Submit(kJob, "job.yaml");
    FAIL() << "submitted without the token";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("token"), std::string::npos) << e.what();
  }
  EXPECT_THROW(api::FarmClient(url, "wrong").Submit(kJob, "job.yaml"), std::invalid_argument);
  EXPECT_NO_THROW(api::FarmClient(url, "s3cret").Submit(kJob, "job.yaml"));
  EXPECT_EQ(anonymous.Jobs().size(), 1u);
}

TEST_F(HttpApiTest, NonLoopbackBindWithoutTokenIsRefused) {
  HttpOptions http;
  http.host = "0.0.0.0";
  try {
    HttpApi api(farm_.get(), http);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--token: required", 0), 0u) << e.what();
  }
  EXPECT_TRUE(IsLoopbackHost("127.0.0.1"));
  EXPECT_TRUE(IsLoopbackHost("127.8.0.1"));
  EXPECT_TRUE(IsLoopbackHost("localhost"));
  EXPECT_FALSE(IsLoopbackHost("10.0.0.1"));
  EXPECT_FALSE(IsLoopbackHost("0.0.0.0"));
}

// POSTs `body` to `path` of the server at `url`; returns status and parsed JSON body.
std::pair<int, nlohmann::json> Post(const std::string& url, const std::string& path,
                                    const std::string& body) {
  httplib::Client client(url);
  const auto res = client.Post(path, body, "application/yaml");
  if (!res) return {-1, nullptr};
  return {res->status, nlohmann::json::parse(res->body, nullptr, /*allow_exceptions=*/false)};
}

TEST_F(HttpApiTest, BodiesAboveTheLimitsAreRefusedWith413NamingTheLimit) {
  HttpOptions limits;
  limits.max_body_bytes = 2048;
  limits.max_policy_bytes = 8192;
  const std::string url = Serve("", limits);
  // Above the job-spec limit, below httplib's cap (the larger of the two): the route refuses.
  const std::string padded = std::string(kJob) + "# " + std::string(4000, 'x') + "\n";
  auto [status, body] = Post(url, "/api/jobs", padded);
  EXPECT_EQ(status, 413);
  EXPECT_EQ(body["limit"], "max-body-bytes") << body.dump();
  EXPECT_NE(body["error"].get<std::string>().find("limit of 2048"), std::string::npos) << body.dump();
  // Above every limit: httplib refuses before reading, still with the JSON message.
  std::tie(status, body) = Post(url, "/api/policies", std::string(10000, '{'));
  EXPECT_EQ(status, 413);
  EXPECT_EQ(body["limit"], "max-body-bytes") << body.dump();
  EXPECT_NE(body["error"].get<std::string>().find("8192"), std::string::npos) << body.dump();
  // A policy between the two limits reaches its own route's check.
  std::tie(status, body) = Post(url, "/api/policies", std::string(5000, '{'));
  EXPECT_EQ(status, 400) << body.dump();  // not refused for size: for not being a policy
  EXPECT_TRUE(store_->jobs().ListJobs(0).empty()) << "a refused request must store nothing";
}

TEST_F(HttpApiTest, JobWithMoreEpisodesThanTheLimitIsRefusedWith413) {
  HttpOptions limits;
  limits.max_job_episodes = 3;
  const std::string url = Serve("", limits);
  auto [status, body] = Post(url, "/api/jobs", kJob);  // 1 x 1 x 2 x 2 = 4 episodes
  EXPECT_EQ(status, 413);
  EXPECT_EQ(body["limit"], "max-job-episodes") << body.dump();
  EXPECT_NE(body["error"].get<std::string>().find("4 episodes, above the server's limit of 3"),
            std::string::npos)
      << body.dump();
  EXPECT_TRUE(store_->jobs().ListJobs(0).empty());
  limits.max_job_episodes = 4;
  api_.reset();
  api::FarmClient client(Serve("", limits));
  EXPECT_EQ(client.Submit(kJob, "job.yaml").episodes, 4) << "a job at the limit is accepted";
}

TEST_F(HttpApiTest, ClientSubmittingTooManyJobsInAMinuteIsRefusedWith429) {
  HttpOptions limits;
  limits.max_jobs_per_minute = 2;
  const std::string url = Serve("", limits);
  api::FarmClient client(url);
  client.Submit(kJob, "a.yaml");
  client.Submit(kJob, "b.yaml");
  auto [status, body] = Post(url, "/api/jobs", kJob);
  EXPECT_EQ(status, 429);
  EXPECT_EQ(body["limit"], "max-jobs-per-minute") << body.dump();
  EXPECT_NE(body["error"].get<std::string>().find("more than 2 jobs in one minute"),
            std::string::npos)
      << body.dump();
  EXPECT_EQ(store_->jobs().ListJobs(0).size(), 2u);
}

TEST(RateLimiterTest, AllowsLimitPerWindowPerKeyAndForgetsOldEvents) {
  using std::chrono::seconds;
  const auto t0 = std::chrono::steady_clock::time_point{} + std::chrono::hours(1);
  RateLimiter limiter(2, seconds(60));
  EXPECT_TRUE(limiter.Allow("a", t0));
  EXPECT_TRUE(limiter.Allow("a", t0 + seconds(10)));
  EXPECT_FALSE(limiter.Allow("a", t0 + seconds(20)));
  EXPECT_TRUE(limiter.Allow("b", t0 + seconds(20))) << "clients are counted apart";
  EXPECT_FALSE(limiter.Allow("a", t0 + seconds(59)));
  EXPECT_TRUE(limiter.Allow("a", t0 + seconds(61))) << "the first event left the window";
  EXPECT_FALSE(limiter.Allow("a", t0 + seconds(62)));
  RateLimiter unlimited(0, seconds(60));
  for (int i = 0; i < 100; ++i) EXPECT_TRUE(unlimited.Allow("a", t0));
}

TEST(FarmClientTest, UnreachableServerIsAFailureNotBadInput) {
  // Port 1 on loopback: nothing listens there.
  api::FarmClient client("http://127.0.0.1:1");
  try {
    client.Jobs();
    FAIL() << "no error";
  } catch (const std::invalid_argument&) {
    FAIL() << "an unreachable server is not the user's bad input";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot reach the farm server at http://127.0.0.1:1", 0), 0u)
        << e.what();
  }
}

TEST(FarmClientTest, MalformedUrlIsBadInput) {
  EXPECT_THROW(api::FarmClient("localhost:8717"), std::invalid_argument);
  EXPECT_THROW(api::FarmClient("http://exa mple"), std::invalid_argument);
  EXPECT_NO_THROW(api::FarmClient("http://farm-server:8717/"));
}

}  // namespace
}  // namespace enavi::server

namespace enavi::server {
namespace {

AccessRequest Get(const std::string& host = "127.0.0.1:8717") {
  AccessRequest r;
  r.method = "GET";
  r.host = host;
  return r;
}

TEST(CheckAccessTest, LoopbackReadsNeedNoTokenButWritesDo) {
  HttpOptions o;
  o.token = "s3cret";
  EXPECT_EQ(CheckAccess(o, Get()).status, 0);
  AccessRequest post = Get();
  post.method = "POST";
  EXPECT_EQ(CheckAccess(o, post).status, 401);
  post.authorization = "Bearer s3cret";
  EXPECT_EQ(CheckAccess(o, post).status, 0);
  post.authorization = "Bearer s3cre";
  EXPECT_EQ(CheckAccess(o, post).status, 401);
  post.authorization.clear();
  post.cookie = "theme=dark; enavi_token=s3cret";
  EXPECT_EQ(CheckAccess(o, post).status, 0);
}

TEST(CheckAccessTest, OffLoopbackEveryRouteNeedsTheToken) {
  HttpOptions o;
  o.host = "10.0.0.10";
  o.token = "s3cret";
  EXPECT_EQ(CheckAccess(o, Get("10.0.0.10:8717")).status, 401);
  AccessRequest with_cookie = Get("10.0.0.10:8717");
  with_cookie.cookie = "enavi_token=s3cret";
  EXPECT_EQ(CheckAccess(o, with_cookie).status, 0);
  AccessRequest login = Get("10.0.0.10:8717");
  login.token_param = "s3cret";
  const AccessDecision d = CheckAccess(o, login);
  EXPECT_EQ(d.status, 0);
  EXPECT_TRUE(d.set_cookie);
  login.token_param = "guess";
  EXPECT_EQ(CheckAccess(o, login).status, 401);
}

TEST(CheckAccessTest, ForeignHostAndCrossOriginWritesAreRefused) {
  HttpOptions o;  // loopback, no token
  EXPECT_EQ(CheckAccess(o, Get("localhost:8717")).status, 0);
  EXPECT_EQ(CheckAccess(o, Get("[::1]:8717")).status, 0);
  EXPECT_EQ(CheckAccess(o, Get("evil.example:8717")).status, 403);  // DNS rebinding
  AccessRequest post = Get();
  post.method = "POST";
  EXPECT_EQ(CheckAccess(o, post).status, 0);  // the CLI sends no Origin
  post.origin = "http://evil.example";
  EXPECT_EQ(CheckAccess(o, post).status, 403);
  post.origin = "http://127.0.0.1:8717";
  EXPECT_EQ(CheckAccess(o, post).status, 0);
}

}  // namespace
}  // namespace enavi::server
