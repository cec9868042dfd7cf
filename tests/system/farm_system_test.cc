// The farm end to end: real `enavi serve` / `enavi worker` processes over DDS, fake episodes.
#include <signal.h>

#include <sstream>
#include <string>
#include <vector>

#include "server/store/jobs.h"
#include "server/store/queries.h"
#include "server/store/store.h"
#include "tests/system/farm_harness.h"

namespace enavi::testing {
namespace {

// Names of the workers running an episode right now.
std::set<std::string> BusyWorkers(api::FarmClient& client) {
  std::set<std::string> busy;
  for (const auto& w : client.Workers()) {
    if (w["alive"].get<bool>() && !w["running"].empty()) busy.insert(w["worker_id"].get<std::string>());
  }
  return busy;
}

TEST_F(FarmFixture, SigkilledWorkerLosesNothingAndDuplicatesNothing) {
  api::FarmClient client(StartServer());
  StartWorker("w1");
  StartWorker("w2");
  ASSERT_TRUE(Eventually([&] { return client.Workers().size() == 2; }, 30s)) << "workers not seen";
  const std::string job = client.Submit(Job(/*seeds=*/2), "system.yaml").job_id;

  // After the first result, kill a worker in the middle of an episode.
  ASSERT_TRUE(Eventually([&] { return client.Status(job).done >= 1 && BusyWorkers(client).count("w1"); },
                         60s));
  Process("w1").Signal(SIGKILL);

  ASSERT_TRUE(Eventually([&] { return client.Status(job).terminal(); }, 120s)) << "job did not finish";
  ExpectExactlyOneResultPerEpisode(client, job, 8);
  // The episode w1 was running when it died was run again (attempt 2) by w2.
  int rerun = 0;
  for (const auto& e : client.Episodes(job)) rerun += e["attempts"].get<int>() > 1 ? 1 : 0;
  EXPECT_GE(rerun, 1) << "the killed worker's episode was not re-run";
}

TEST_F(FarmFixture, SigkilledAndRestartedServerLosesNothingAndDuplicatesNothing) {
  StartServer();
  api::FarmClient before(url_);
  StartWorker("w1");
  StartWorker("w2");
  ASSERT_TRUE(Eventually([&] { return before.Workers().size() == 2; }, 30s)) << "workers not seen";
  const std::string job = before.Submit(Job(/*seeds=*/2), "system.yaml").job_id;
  ASSERT_TRUE(Eventually([&] { return before.Status(job).done >= 2; }, 60s));

  // Kill the server mid-job; the workers finish what they run and keep those results.
  Process("server").Signal(SIGKILL);
  Process("server").Wait(std::chrono::milliseconds::max());
  std::this_thread::sleep_for(2500ms);

  api::FarmClient after(StartServer());  // same database, new port
  ASSERT_TRUE(Eventually([&] { return after.Status(job).terminal(); }, 120s)) << "job did not finish";
  ExpectExactlyOneResultPerEpisode(after, job, 8);
  // Results finished while the server was down arrived after the restart: nothing had to run
  // twice, and the running leases survived the restart.
  for (const auto& e : after.Episodes(job)) {
    EXPECT_EQ(e["attempts"].get<int>(), 1) << e.dump();
  }
}

TEST_F(FarmFixture, CrashingEpisodesAreRetriedThenFailWithTheReason) {
  api::FarmClient client(StartServer());
  // Always the fake: the crashes are asked for through its tunables.
  StartWorker("w1", /*slots=*/2, /*episode_s=*/0, FakeEpisode().string());
  ASSERT_TRUE(Eventually([&] { return client.Workers().size() == 1; }, 30s));
  // Seed 1 crashes on attempts 1 and 2 (then succeeds); seed 2 always crashes.
  const std::string spec = R"(name: crashy
boards: [tx2]
scenarios: [s1]
methods: [enavi]
seeds: [1, 2]
episode_overrides:
  - match: {seed: 1}
    overrides: {fake.crash_attempts: 2}
  - match: {seed: 2}
    overrides: {fake.crash_attempts: 99}
)";
  const std::string job = client.Submit(spec, "crashy.yaml").job_id;
  ASSERT_TRUE(Eventually([&] { return client.Status(job).terminal(); }, 60s));
  const api::JobProgress p = client.Status(job);
  EXPECT_EQ(p.done, 1);
  EXPECT_EQ(p.failed, 1);
  ASSERT_EQ(p.errors.size(), 1u);
  EXPECT_NE(p.errors[0].find("killed by signal 6"), std::string::npos) << p.errors[0];
  EXPECT_NE(p.errors[0].find("gave up after 3 attempts"), std::string::npos) << p.errors[0];
  EXPECT_TRUE(Process("w1").running()) << "crashing episodes must not take the worker down";
}

// Runs `enavi eval ARGS...` with the fake episode (real_episodes: `enavi episode`, real flights)
// on this test's domain. It must succeed. Returns its stdout, the table. Its stderr is in
// DIR/NAME.log.
std::string EvalOutput(const fs::path& dir, const std::string& name, std::vector<std::string> args,
                       int domain, std::chrono::seconds limit, bool real_episodes = false) {
  worker::SpawnOptions o;
  o.argv = {EnaviBinary().string(), "eval"};
  o.argv.insert(o.argv.end(), args.begin(), args.end());
  if (!real_episodes) o.argv.insert(o.argv.end(), {"--episode-cmd", EpisodeCommand()});
  o.argv.insert(o.argv.end(), {"--domain", std::to_string(domain)});
  o.stdout_file = dir / (name + ".out");
  o.stderr_file = dir / (name + ".log");
  worker::ChildProcess eval = worker::ChildProcess::Spawn(o);
  const auto status = eval.Wait(limit);
  if (!status) {
    ADD_FAILURE() << "enavi eval (" << name << ") did not finish";
    return "";
  }
  EXPECT_TRUE(status->ok()) << status->Describe() << "\n" << ReadText(o.stderr_file);
  return ReadText(o.stdout_file);
}

TEST_F(FarmFixture, EvalStoresEveryResultAndPrintsThePaperTable) {
  const fs::path db = dir_ / "eval.db";
  const std::string table = EvalOutput(dir_, "eval",
                                       {"--boards", "tx2", "--scenarios", "s1", "--methods", "enavi,baseline",
                                        "--seeds", "2", "--db", db.string(), "--workers", "2"},
                                       domain_, std::chrono::seconds(180));
  EXPECT_NE(table.find("tx2    baseline"), std::string::npos) << table;
  EXPECT_NE(table.find("tx2    enavi"), std::string::npos) << table;
  EXPECT_NE(table.find("E-Navi vs baseline"), std::string::npos) << table;

  server::Store store(db);
  const auto jobs = store.jobs().ListJobs(0);
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].done, 4);
  EXPECT_EQ(store.queries().Results(jobs[0].id).size(), 4u);
}

TEST_F(FarmFixture, EvalPresetPaperRunsThePapersMatrixAndPrintsOursBesideIt) {
  const fs::path db = dir_ / "paper.db";
  const std::string out = EvalOutput(dir_, "paper",
                                     {"--preset", "paper", "--seeds", "1", "--db", db.string(), "--workers", "2",
                                      "--slots", "2"},
                                     domain_, std::chrono::seconds(240));
  for (const char* title : {"nav cpu % of one core: ours beside the paper's HIL table",
                            "flight time s: ours beside the paper's HIL table", "path m: ours beside the paper's HIL table"}) {
    EXPECT_NE(out.find(title), std::string::npos) << out;
  }
  // The paper's x86 S1 CPU cells (baseline 42.5, E-Navi 38.2) are printed beside ours.
  EXPECT_NE(out.find("42.5"), std::string::npos) << out;
  EXPECT_NE(out.find("38.2"), std::string::npos) << out;
  for (const char* board : {"pi4b ", "tx2 ", "nx ", "opi5 ", "x86 "}) {
    const std::size_t reductions = out.find("E-Navi vs baseline, mean of the scenario means");
    ASSERT_NE(reductions, std::string::npos) << out;
    EXPECT_NE(out.find(std::string("\n") + board, reductions), std::string::npos) << board << "\n" << out;
  }
  server::Store store(db);
  const auto jobs = store.jobs().ListJobs(0);
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(store.queries().Results(jobs[0].id).size(), 50u) << "5 boards x 5 scenarios x 2 methods x 1 seed";
}

// Runs `enavi ARGS...`, which must refuse the request: exit 2 and `message` on stderr.
void ExpectRefused(const fs::path& dir, const std::vector<std::string>& args, const std::string& message) {
  worker::SpawnOptions o;
  o.argv = {EnaviBinary().string()};
  o.argv.insert(o.argv.end(), args.begin(), args.end());
  o.stderr_file = dir / (args.front() + ".err");
  worker::ChildProcess child = worker::ChildProcess::Spawn(o);
  const auto status = child.Wait(std::chrono::seconds(60));
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->code, 2) << status->Describe();
  EXPECT_NE(ReadText(o.stderr_file).find(message), std::string::npos) << ReadText(o.stderr_file);
}

// `enavi eval --set`: NAME=VALUE reaches every method's episodes, METHOD:NAME=VALUE one method's.
// The fake episode's knobs pass as `--unchecked-overrides`. The table's first line names both.
TEST_F(FarmFixture, EvalSetOverridesReachTheEpisodesTheyName) {
  const fs::path db = dir_ / "set.db";
  const std::string every = "fake.sleep_s=0.1", enavi_only = "enavi:fake.crash_attempts=1";
  const std::vector<std::string> args = {"--boards", "tx2", "--scenarios", "s1", "--methods", "baseline,enavi",
                                         "--set", every, "--set", enavi_only, "--unchecked-overrides", "fake.",
                                         "--db", db.string()};
  const std::string table = EvalOutput(dir_, "set", args, domain_, std::chrono::seconds(180));
  const std::string header = "with --set " + every + " --set " + enavi_only;
  EXPECT_EQ(table.rfind(header, 0), 0u) << table;
  server::Store store(db);
  const auto jobs = store.jobs().ListJobs(0);
  ASSERT_EQ(jobs.size(), 1u);
  const auto episodes = store.jobs().Episodes(jobs[0].id);
  ASSERT_EQ(episodes.size(), 2u);
  for (const auto& e : episodes) {
    EXPECT_EQ(e.spec.overrides.at("fake.sleep_s"), 0.1) << e.spec.method;
    EXPECT_EQ(e.spec.overrides.count("fake.crash_attempts"), e.spec.method == "enavi" ? 1u : 0u) << e.spec.method;
    EXPECT_EQ(e.attempts, e.spec.method == "enavi" ? 2 : 1) << e.spec.method << ": one crash, then done";
  }
}

TEST_F(FarmFixture, EvalSetRefusesAMethodNotFlownAndATunableNotAllTake) {
  ExpectRefused(dir_, {"eval", "--set", "fixed:planner.v_max=1"},
                "--set fixed:planner.v_max: method 'fixed' is not among --methods (baseline,enavi)");
  ExpectRefused(dir_, {"eval", "--set", "strategy.least_load=1"},
                "--set strategy.least_load: not a tunable of method baseline");
  ExpectRefused(dir_, {"eval", "--set", "enavi:strategy.least_load=on"},
                "--set enavi:strategy.least_load: 'on' is not a number");
}

// A policy file that does not load is refused at submit, before any episode flies it.
TEST_F(FarmFixture, EvalRefusesAPolicyThatDoesNotLoadByName) {
  std::ofstream(dir_ / "policy.json") << "{}";
  ExpectRefused(dir_, {"eval", "--policy", (dir_ / "policy.json").string(), "--world-root", dir_.string()},
                "policy file '" + (dir_ / "policy.json").string() + "': format: missing");
}

TEST_F(FarmFixture, EvalPresetPaperRefusesAnotherMatrix) {
  ExpectRefused(dir_, {"eval", "--preset", "paper", "--boards", "x86"},
                "--preset paper fixes the boards and scenarios; drop --boards");
}

TEST_F(FarmFixture, EvalRefusesASpeedProbeOnTheVirtualClockByName) {
  ExpectRefused(dir_, {"eval", "--speed-probe", "use"},
                "--speed-probe use: the emulated clock's (this job's clock is virtual)");
}

// `enavi eval --name` names the job; in a log (stderr not a terminal) progress is a line at the
// start, at each tenth of the job and at its end, not only the final line (issue 44).
TEST_F(FarmFixture, EvalNamesTheJobAndPrintsProgressLinesInALog) {
  const fs::path db = dir_ / "named.db";
  EvalOutput(dir_, "named",
             {"--name", "nightly-1", "--boards", "tx2", "--scenarios", "s1", "--methods", "baseline,enavi",
              "--seeds", "5", "--db", db.string(), "--set", "fake.sleep_s=0.3", "--unchecked-overrides", "fake."},
             domain_, std::chrono::seconds(180));
  std::istringstream log(ReadText(dir_ / "named.log"));
  std::vector<std::string> lines;
  for (std::string line; std::getline(log, line);) {
    if (line.find("/10 done") != std::string::npos) lines.push_back(line);
  }
  ASSERT_GE(lines.size(), 3u) << ReadText(dir_ / "named.log");
  EXPECT_NE(lines.front().find(" 0/10 done"), std::string::npos) << lines.front();
  EXPECT_NE(lines.back().find(" 10/10 done"), std::string::npos) << lines.back();
  EXPECT_EQ(lines.back().find('\r'), std::string::npos) << "lines, not a bar redrawn in place";
  server::Store store(db);
  const auto jobs = store.jobs().ListJobs(0);
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].name, "nightly-1");
}

// Issue 44's case on real flights: two one-seed evals of s1 on tx2, the second with
// --set planner.v_max=1.0, compared in paired mode. It printed "no regression" and exited 0 with
// flight time +131 %; now the mode says it cannot judge (exit 4) and names the override first.
TEST_F(FarmFixture, PairedCompareOfTwoOneSeedEvalsCannotJudgeAndNamesTheOverride) {
  const fs::path db = dir_ / "a.db";
  const std::vector<std::string> matrix = {"--boards", "tx2", "--scenarios", "s1", "--seeds", "1", "--db", db.string()};
  std::vector<std::string> slow = matrix;
  slow.insert(slow.end(), {"--name", "slow", "--set", "planner.v_max=1.0"});
  EvalOutput(dir_, "before", matrix, domain_, std::chrono::seconds(300), /*real_episodes=*/true);
  EvalOutput(dir_, "slow", slow, domain_, std::chrono::seconds(300), /*real_episodes=*/true);
  std::vector<std::string> ids;
  {
    server::Store store(db);
    for (const auto& p : store.jobs().ListJobs(0)) ids.push_back(p.id);
  }
  ASSERT_EQ(ids.size(), 2u);
  worker::SpawnOptions o;
  o.argv = {EnaviBinary().string(), "compare", db.string() + ":" + ids[0], db.string() + ":" + ids[1], "--mode",
            "paired"};
  o.stdout_file = dir_ / "compare.out";
  worker::ChildProcess compare = worker::ChildProcess::Spawn(o);
  const auto status = compare.Wait(std::chrono::seconds(60));
  ASSERT_TRUE(status.has_value());
  const std::string out = ReadText(o.stdout_file);
  EXPECT_EQ(status->code, 4) << status->Describe() << "\n" << out;
  EXPECT_NE(out.find("overrides.planner.v_max in 2 of 2 cells: (default) -> 1.0"), std::string::npos) << out;
  EXPECT_NE(out.find("TOO_FEW_PAIRS  flight_time_s"), std::string::npos) << out;
  EXPECT_NE(out.find("CANNOT JUDGE: "), std::string::npos) << out;
  EXPECT_EQ(out.find("no regression"), std::string::npos) << out;
}

TEST_F(FarmFixture, BadJobSpecIsRejectedByTheCliWithExitCodeTwo) {
  StartServer();
  std::ofstream(dir_ / "bad.yaml") << "boards: [tx2]\nscenarios: [s1]\nmethods: [enavi]\nseeds: -1\n";
  ExpectRefused(dir_, {"submit", (dir_ / "bad.yaml").string(), "--server", url_},
                "bad.yaml:4: seeds: count -1 outside [1, 1000]");
}

}  // namespace
}  // namespace enavi::testing
