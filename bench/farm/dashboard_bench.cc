// The dashboard's job page against a 10 000-episode job (5 boards x 5 scenarios x 2 methods x
// 200 seeds, synthetic results with 50-sample series): the four requests the page makes (job
// progress, per-cell summary computed in SQLite, failures, first page of results), over HTTP on
// loopback, as the browser makes them. Reference in the same run: GET /api/health, the
// cheapest round-trip of the same server. Goal: the page's requests answer in < 100 ms (p95).
//
//   bench_dashboard [--benchmark_filter=...]
// Each repetition is one page load; p95 is over the repetitions.
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include <benchmark/benchmark.h>
#include <httplib.h>

#include "server/http/http_api.h"
#include "server/store/store.h"
#include "tests/support/seed_store.h"

namespace enavi {
namespace {

namespace fs = std::filesystem;

constexpr const char* kJob = R"(name: bench-10k
labels: {suite: bench}
boards: [pi4b, tx2, nx, opi5, x86]
scenarios: [s1, s2, s3, s4, s5]
methods: [baseline, enavi]
seeds: 200
)";

// One read-only dashboard over a seeded database, shared by every benchmark.
struct Fixture {
  Fixture() {
    dir = fs::temp_directory_path() / ("bench_dashboard-" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    {
      server::Store writer(dir / "farm.db");
      job = testing::SeedJob(writer, kJob, 1764547200000);
    }
    server::StoreOptions ro;
    ro.read_only = true;
    store = std::make_unique<server::Store>(dir / "farm.db", ro);
    api = std::make_unique<server::HttpApi>(store.get(), server::HttpOptions{});
    port = api->Start();
  }
  ~Fixture() {
    api.reset();
    store.reset();
    fs::remove_all(dir);
  }
  fs::path dir;
  std::string job;
  std::unique_ptr<server::Store> store;
  std::unique_ptr<server::HttpApi> api;
  int port = 0;
};

Fixture& Shared() {
  static Fixture f;
  return f;
}

void Get(httplib::Client& client, const std::string& path, benchmark::State& state) {
  const auto res = client.Get(path.c_str());
  if (!res || res->status != 200) {
    state.SkipWithError(("GET " + path + " failed").c_str());
    return;
  }
  benchmark::DoNotOptimize(res->body.size());
}

void BM_JobPage(benchmark::State& state) {
  Fixture& f = Shared();
  httplib::Client client("127.0.0.1", f.port);
  for (auto _ : state) {
    Get(client, "/api/jobs/" + f.job, state);
    Get(client, "/api/jobs/" + f.job + "/summary?limit=1000", state);
    Get(client, "/api/jobs/" + f.job + "/failures?limit=200", state);
    Get(client, "/api/jobs/" + f.job + "/results?offset=0&limit=50", state);
  }
}

// One request of the page at a time (argument: 0 progress, 1 summary, 2 failures, 3 results).
void BM_JobPageRequest(benchmark::State& state) {
  Fixture& f = Shared();
  const std::string paths[] = {"", "/summary?limit=1000", "/failures?limit=200", "/results?offset=0&limit=50"};
  const std::string path = "/api/jobs/" + f.job + paths[state.range(0)];
  httplib::Client client("127.0.0.1", f.port);
  for (auto _ : state) Get(client, path, state);
}

void BM_HealthReference(benchmark::State& state) {
  Fixture& f = Shared();
  httplib::Client client("127.0.0.1", f.port);
  for (auto _ : state) Get(client, "/api/health", state);
}

double P95(const std::vector<double>& v) {
  std::vector<double> s = v;
  std::sort(s.begin(), s.end());
  return s[std::min(s.size() - 1, static_cast<std::size_t>(0.95 * s.size()))];
}

BENCHMARK(BM_JobPage)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(60)
    ->ComputeStatistics("p95", P95)->DisplayAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_JobPageRequest)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(60)
    ->ComputeStatistics("p95", P95)->DisplayAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_HealthReference)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(60)
    ->ComputeStatistics("p95", P95)->DisplayAggregatesOnly(true)->UseRealTime();

}  // namespace
}  // namespace enavi

BENCHMARK_MAIN();
