// Result ingestion, end to end on one host: a worker publishes N results over DDS (reliable,
// transient-local, with time series), the farm server takes them, inserts them into SQLite
// (WAL, synchronous=FULL, batched transactions) and acknowledges each; the clock stops when the
// last acknowledgement is back at the worker. Goal: >= 1000 results/s.
//
//   bench_farm_ingest [--benchmark_filter=...]
//   Arguments: series samples per result (0, 400 = 10 Hz x 40 s flight, 1200 = 30 Hz x 40 s).
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <thread>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "api/dds_config.h"
#include "api/farm_bus.h"
#include "server/scheduler/farm_server.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/queries.h"
#include "server/store/store.h"

namespace enavi {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kResults = 2000;

api::EpisodeResult RealisticResult(const api::EpisodeSpec& spec, int samples) {
  api::EpisodeResult r;
  r.spec = spec;
  r.scenario = spec.world;
  r.success = true;
  r.end_reason = "goal_reached";
  r.flight_time_s = 38.2;
  r.path_length_m = 45.1;
  r.straight_line_m = 42.0;
  r.velocity_mean_mps = 1.2;
  r.velocity_std_mps = 0.4;
  r.accel_peak_mps2 = 3.1;
  r.task_cpu_util_pct = {{"perception", 42.0}, {"planning", 21.0}, {"collision", 9.0}, {"difference", 4.0}};
  r.nav_cpu_util_pct = 42.0 + 21.0 + 9.0 + 4.0;
  r.jobs_released = 2400;
  r.deadline_misses = 12;
  r.deadline_miss_ratio = 0.005;
  r.replans = 31;
  r.eci = {0.06, 0.41, 0.87};
  r.notes = {{"clock", "virtual"}, {"cost", "model"}, {"calibration", "host-abc123"}};
  for (int i = 0; i < 31; ++i) r.events.push_back({1.2 * i, "replan", "collision_trigger"});
  for (int i = 0; i < samples; ++i) {
    const double t = 0.1 * i;
    r.series.t.push_back(t);
    r.series.position.push_back({t, 0.3 * t, 1.5});
    r.series.velocity.push_back({1.1, 0.2, 0.01});
    r.series.eci.push_back(0.4);
    r.series.f_per.push_back(20);
    r.series.f_col.push_back(10);
    r.series.f_dif.push_back(10);
    r.series.res.push_back(0.2);
    r.series.utilisation.push_back(70);
  }
  return r;
}

void BM_ResultIngestion(benchmark::State& state) {
  const int samples = static_cast<int>(state.range(0));
  const fs::path dir = fs::temp_directory_path() / ("bench_farm_ingest-" + std::to_string(getpid()));
  api::BusOptions bus;
  bus.domain_id = 200 + static_cast<std::uint32_t>(getpid()) % 30;
  bus.partition = "bench-" + std::to_string(getpid()) + "-" + std::to_string(samples);
  api::DdsNetwork net;
  net.loopback = true;
  bus.config_xml = api::CycloneConfigXml(net);

  spdlog::set_level(spdlog::level::warn);  // the server's per-job log lines
  std::size_t bytes_per_result = 0;
  for (auto _ : state) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    server::Store store(dir / "farm.db");
    // A job whose episodes are all leased to the bench worker (not timed).
    std::vector<api::EpisodeSpec> specs(kResults);
    for (int i = 0; i < kResults; ++i) specs[i].seed = static_cast<std::uint64_t>(i + 1);
    const std::string job = store.jobs().CreateJob("bench", "bench", specs, server::NowMs());
    const auto leases =
        store.leases().LeaseEpisodes("bench-w", kResults, {}, server::NowMs() + 3600'000, server::NowMs());
    std::vector<api::ResultMessage> messages;
    for (const auto& l : leases) {
      api::ResultMessage m;
      m.episode_id = l.episode_id;
      m.attempt = l.attempt;
      m.worker_id = "bench-w";
      m.job_id = job;
      m.wall_time_s = 40;
      m.result = RealisticResult(l.spec, samples);
      messages.push_back(std::move(m));
    }
    bytes_per_result = api::ToJson(messages.front()).dump().size();

    server::FarmServerOptions options;
    options.bus = bus;
    server::FarmServer farm(&store, options);
    farm.Start();
    api::WorkerBus worker(bus, "bench-w");
    while (worker.MatchedServers() == 0) std::this_thread::sleep_for(1ms);
    std::this_thread::sleep_for(200ms);  // let every endpoint pair match

    // The worker side as in production: publish, and retire each result once acknowledged.
    std::atomic<int> acked{0};
    std::atomic<bool> done{false};
    std::thread ack_thread([&] {
      std::map<std::string, const api::ResultMessage*> by_id;
      for (const auto& m : messages) by_id[m.episode_id] = &m;
      while (!done) {
        for (const auto& ack : worker.Wait(50ms).acks) {
          worker.Retire(*by_id.at(ack.episode_id));
          ++acked;
        }
        if (acked.load() >= kResults) done = true;
      }
    });
    const auto start = std::chrono::steady_clock::now();
    for (const auto& m : messages) worker.Publish(m);
    ack_thread.join();
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(elapsed);
    farm.Stop();
    if (store.queries().Results(job).size() != static_cast<std::size_t>(kResults)) {
      state.SkipWithError("not every result was stored");
    }
  }
  fs::remove_all(dir);
  state.counters["results_per_s"] =
      benchmark::Counter(kResults, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["result_json_kB"] = bytes_per_result / 1000.0;  // its JSON (spool) size
  state.SetBytesProcessed(state.iterations() * kResults * static_cast<std::int64_t>(bytes_per_result));
}

BENCHMARK(BM_ResultIngestion)
    ->ArgName("series_samples")
    ->Arg(0)
    ->Arg(400)
    ->Arg(1200)
    ->Iterations(1)
    ->Repetitions(3)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace enavi

BENCHMARK_MAIN();
