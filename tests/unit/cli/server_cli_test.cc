// The farm's commands as a newcomer meets them (issue 44): a listener refuses a port in use,
// `enavi compare` fails closed and says how the jobs differ, bad input exits 2 naming what was
// typed, `enavi --version`. Runs the built binary on databases seeded with synthetic results.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/store/store.h"
#include "tests/support/seed_store.h"
#include "workers/worker/process.h"

namespace enavi::cli {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Two one-seed jobs of s1 on tx2, the second flown with planner.v_max 1.0 (the synthetic result
// doubles its flight time, as the real planner's flight roughly does).
constexpr const char* kBefore = "name: before\nboards: [tx2]\nscenarios: [s1]\nmethods: [baseline, enavi]\nseeds: 1\n"
                                "labels: {run: fast}\n";
constexpr const char* kSlow = "name: slow\nboards: [tx2]\nscenarios: [s1]\nmethods: [baseline, enavi]\nseeds: 1\n"
                              "labels: {run: slow}\noverrides: {planner.v_max: 1.0}\n";

struct CliRun {
  int code = -1;
  std::string out, err;
};

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class ServerCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("server_cli_test-" + std::to_string(getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    server::Store store(db());
    before_ = testing::SeedJob(store, kBefore, 1000);
    slow_ = testing::SeedJob(store, kSlow, 2000);
  }
  void TearDown() override {
    children_.clear();  // kills what is still running
    fs::remove_all(dir_);
  }
  fs::path db() const { return dir_ / "a.db"; }
  std::string Job(const std::string& id) const { return db().string() + ":" + id; }

  // `enavi ARGS...` to completion.
  CliRun Enavi(const std::vector<std::string>& args) {
    worker::SpawnOptions o;
    o.argv = {std::string(ENAVI_BINARY_DIR) + "/bin/enavi"};
    o.argv.insert(o.argv.end(), args.begin(), args.end());
    o.stdout_file = dir_ / "out.txt";
    o.stderr_file = dir_ / "err.txt";
    worker::ChildProcess child = worker::ChildProcess::Spawn(o);
    const auto status = child.Wait(60s);
    CliRun r;
    if (status && status->exited) r.code = status->code;
    r.out = ReadText(o.stdout_file);
    r.err = ReadText(o.stderr_file);
    return r;
  }

  // `enavi ARGS... --ready-file F` left running; returns the URL it serves once ready.
  std::string Serve(const std::string& name, std::vector<std::string> args) {
    const fs::path ready = dir_ / (name + ".ready");
    args.insert(args.end(), {"--ready-file", ready.string()});
    worker::SpawnOptions o;
    o.argv = {std::string(ENAVI_BINARY_DIR) + "/bin/enavi"};
    o.argv.insert(o.argv.end(), args.begin(), args.end());
    o.stderr_file = dir_ / (name + ".log");
    children_.push_back(worker::ChildProcess::Spawn(o));
    for (int i = 0; i < 400; ++i) {
      const std::string url = ReadText(ready);
      if (!url.empty()) return url.substr(0, url.find('\n'));
      if (!children_.back().running()) break;
      std::this_thread::sleep_for(50ms);
    }
    ADD_FAILURE() << name << " did not start: " << ReadText(o.stderr_file);
    return "";
  }

  fs::path dir_;
  std::string before_, slow_;
  std::vector<worker::ChildProcess> children_;
};

// Issue 44, 1: a second server on a port in use used to start (httplib set SO_REUSEPORT) and
// share the port with the first, each answering from its own database.
TEST_F(ServerCliTest, ASecondListenerOnAPortInUseExitsNamingTheAddress) {
  const std::string url = Serve("dashboard", {"dashboard", "--db", db().string(), "--http", "127.0.0.1:0"});
  ASSERT_FALSE(url.empty());
  const std::string address = url.substr(std::string("http://").size());
  const CliRun dashboard = Enavi({"dashboard", "--db", db().string(), "--http", address});
  EXPECT_EQ(dashboard.code, 1) << dashboard.err;
  EXPECT_NE(dashboard.err.find("cannot listen on " + address + ": address already in use"), std::string::npos)
      << dashboard.err;
  const CliRun serve = Enavi({"serve", "--db", (dir_ / "other.db").string(), "--http", address, "--domain",
                           std::to_string(20 + getpid() % 100)});
  EXPECT_EQ(serve.code, 1) << serve.err;
  EXPECT_NE(serve.err.find("cannot listen on " + address + ": address already in use"), std::string::npos) << serve.err;
  // The first one still serves its own database.
  const CliRun status = Enavi({"status", "--server", url});
  EXPECT_EQ(status.code, 0) << status.err;
  EXPECT_NE(status.out.find(before_), std::string::npos) << status.out;
}

// Issue 44, 2: paired mode with one seed pair has no interval; it said "no regression" and exited
// 0 with flight time doubled, and the override that did it appeared nowhere.
TEST_F(ServerCliTest, CompareFailsClosedWhenTheModeCannotJudgeAndSaysHowTheJobsDiffer) {
  const CliRun paired = Enavi({"compare", Job(before_), Job(slow_), "--mode", "paired"});
  EXPECT_EQ(paired.code, 4) << paired.out << paired.err;
  EXPECT_NE(paired.out.find("CANNOT JUDGE: "), std::string::npos) << paired.out;
  EXPECT_EQ(paired.out.find("no regression"), std::string::npos) << paired.out;
  const std::size_t differ = paired.out.find("how the jobs differ");
  ASSERT_NE(differ, std::string::npos) << paired.out;
  EXPECT_NE(paired.out.find("overrides.planner.v_max in 2 of 2 cells: (default) -> 1.0"), std::string::npos)
      << paired.out;
  EXPECT_NE(paired.out.find("label.run: fast -> slow"), std::string::npos) << paired.out;
  EXPECT_LT(differ, paired.out.find("tx2/s1/baseline")) << "before the metrics:\n" << paired.out;

  // Exact mode, the default on the virtual clock, calls it: exit 3.
  const CliRun exact = Enavi({"compare", Job(before_), Job(slow_)});
  EXPECT_EQ(exact.code, 3) << exact.out << exact.err;
  EXPECT_NE(exact.out.find("REGRESSION: "), std::string::npos) << exact.out;

  // The JSON (the dashboard's compare view reads the same from GET /api/compare) and JUnit.
  const CliRun json = Enavi({"compare", Job(before_), Job(slow_), "--mode", "paired", "--format", "json"});
  EXPECT_EQ(json.code, 4);
  const nlohmann::json report = nlohmann::json::parse(json.out);
  EXPECT_EQ(report["verdict"], "cannot_judge");
  EXPECT_EQ(report["spec_changes"][0]["name"], "overrides.planner.v_max");
  const CliRun junit = Enavi({"compare", Job(before_), Job(slow_), "--mode", "paired", "--format", "junit"});
  EXPECT_EQ(junit.code, 4);
  EXPECT_NE(junit.out.find("<property name=\"overrides.planner.v_max\""), std::string::npos) << junit.out;
  EXPECT_NE(junit.out.find("type=\"cannot_judge\""), std::string::npos) << junit.out;

  // The same jobs compared with themselves: no change, exit 0, in either mode.
  const CliRun same = Enavi({"compare", Job(before_), Job(before_), "--mode", "paired"});
  EXPECT_EQ(same.code, 0) << same.out;
  EXPECT_NE(same.out.find("no change"), std::string::npos) << same.out;
}

// Issue 44, 3: each error names what the user typed and exits 2.
TEST_F(ServerCliTest, BadInputNamesWhatWasTypedAndExitsTwo) {
  // A file name was taken for a job id and sent to a server that was not there (exit 1).
  CliRun r = Enavi({"compare", "nonexist.db", Job(before_)});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("BASE: 'nonexist.db': no such database file"), std::string::npos) << r.err;
  r = Enavi({"compare", Job(before_), "nonexist.db:" + slow_});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("CANDIDATE: 'nonexist.db:" + slow_ + "': no such database file 'nonexist.db'"),
            std::string::npos)
      << r.err;
  // A metric no result has printed "no results" and exited 0.
  r = Enavi({"trend", "--label", "run=slow", "--metric", "flight_time", "--db", db().string()});
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--metric: 'flight_time': no result of the jobs labelled run=slow has it; did you mean "
                       "flight_time_s?"),
            std::string::npos)
      << r.err;
  r = Enavi({"trend", "--label", "run=medium", "--db", db().string()});
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--label: 'run=medium': no job carries this label"), std::string::npos) << r.err;
  r = Enavi({"trend", "--label", "run=slow", "--db", db().string()});
  EXPECT_EQ(r.code, 0) << r.err;
  // `enavi eval` cited a line of the YAML it wrote itself ("enavi eval flags:8").
  r = Enavi({"eval", "--set", "planner.v_maxx=1.0"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("error: --set planner.v_maxx: not a tunable of method baseline"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("eval flags"), std::string::npos) << r.err;
  r = Enavi({"eval", "--scenarios", "s1,s9"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("error: --scenarios s1,s9: "), std::string::npos) << r.err;
}

TEST_F(ServerCliTest, VersionNamesTheVersionAndTheCommit) {
  const CliRun r = Enavi({"--version"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("enavi ", 0), 0u) << r.out;
  EXPECT_NE(r.out.find(" (commit "), std::string::npos) << r.out;
}

}  // namespace
}  // namespace enavi::cli
