// A rogue worker's result sample on its way into the store: api::ResultFromSample (the decoder
// of what Cyclone DDS delivers), then server::ResultIngest::Ingest with its validation, against a fresh
// job whose one episode is leased to worker w1. The input drives every field of the sample:
// another episode's id or attempt, a huge time series, NaN and infinite metrics, malformed
// result JSON. A sample is refused or handled; a stored result is always the leased episode's,
// finite and consistent, and nothing else is ever stored.

#include <fuzzer/FuzzedDataProvider.h>

#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/farm_samples.h"
#include "api/result_metrics.h"
#include "server/store/ingest.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/queries.h"
#include "server/store/store.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using namespace enavi;

constexpr std::int64_t kNow = 1'000'000;

server::Store& TheStore() {
  static const std::unique_ptr<server::Store> store = [] {
    // tmpfs when there is one: every ingest is a synchronous transaction.
    const std::filesystem::path shm = "/dev/shm";
    const auto dir = (std::filesystem::exists(shm) ? shm : std::filesystem::temp_directory_path()) /
                     ("enavi-fuzz-store-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return std::make_unique<server::Store>(dir / "farm.db");
  }();
  return *store;
}

// Any double, NaN and infinities included (FuzzedDataProvider's floats are finite).
double AnyDouble(FuzzedDataProvider* in) {
  if (in->ConsumeBool()) return in->ConsumeFloatingPointInRange<double>(-1e3, 1e3);
  return std::bit_cast<double>(in->ConsumeIntegral<std::uint64_t>());
}

// A sequence<double> whose buffer `store` owns: short and arbitrary, or occasionally huge.
dds_sequence_double Doubles(FuzzedDataProvider* in, std::vector<double>* store) {
  const std::size_t n = in->ConsumeIntegralInRange<std::size_t>(0, 8);
  for (std::size_t i = 0; i < n; ++i) store->push_back(AnyDouble(in));
  if (in->ConsumeIntegralInRange<int>(0, 15) == 0) store->resize(in->ConsumeIntegralInRange<std::size_t>(0, 300'000), 0.5);
  dds_sequence_double seq{};
  seq._length = seq._maximum = static_cast<std::uint32_t>(store->size());
  seq._buffer = store->empty() ? nullptr : store->data();
  return seq;
}

// The result JSON a worker sends: a well-formed one for `spec` with fuzzed metrics and spec
// fields, or raw bytes.
std::string ResultJson(FuzzedDataProvider* in, const api::EpisodeSpec& spec) {
  if (in->ConsumeBool()) return in->ConsumeRandomLengthString(512);
  api::EpisodeResult r;
  r.spec = spec;
  if (in->ConsumeBool()) r.spec.board = in->PickValueInArray({"tx2", "pi4b", "x86"});
  if (in->ConsumeBool()) r.spec.seed = in->ConsumeIntegralInRange<std::uint64_t>(0, 3);
  r.success = in->ConsumeBool();
  r.flight_time_s = AnyDouble(in);
  r.path_length_m = AnyDouble(in);
  r.nav_cpu_util_pct = AnyDouble(in);
  r.eci.mean = AnyDouble(in);
  nlohmann::json j = api::ResultSummaryJson(r);
  j["spec"] = r.spec;
  // nlohmann writes NaN as null; a rogue worker writes what it likes.
  std::string text = j.dump();
  if (in->ConsumeBool()) {
    const std::string token = in->PickValueInArray({"1e999", "-1e999", "NaN", "1e308", "-0"});
    const auto at = text.find("\"flight_time_s\":");
    text.replace(at + 16, text.find(',', at) - at - 16, token);
  }
  return text;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  server::Store& store = TheStore();
  api::EpisodeSpec spec;
  spec.board = "tx2";
  spec.method = "enavi";
  const std::string job = store.jobs().CreateJob("fuzz", "fuzz", {spec}, kNow);
  const auto leases = store.leases().LeaseEpisodes("w1", 1, {}, kNow + 15'000, kNow);
  fuzz::Check(leases.size() == 1, "the fresh job's episode is not leased");
  const server::Lease& lease = leases[0];

  // The sample, every field from the input.
  std::deque<std::string> strings;  // the sample's char* point into these: no reallocation
  const auto text = [&](std::string s) { return strings.emplace_back(std::move(s)).data(); };
  enavi_farm_EpisodeResult c{};
  c.episode_id = text(in.ConsumeBool() ? lease.episode_id : in.ConsumeRandomLengthString(40));
  c.attempt = in.ConsumeBool() ? lease.attempt : in.ConsumeIntegral<std::int32_t>();
  c.worker_id = text(in.ConsumeBool() ? "w1" : in.ConsumeRandomLengthString(16));
  c.job_id = text(job);
  // Cyclone DDS refuses enum values outside the IDL's on deserialisation; 3 is the one value
  // past them a C++ enum of three enumerators can hold.
  c.status = static_cast<enavi_farm_ResultStatus>(in.ConsumeIntegralInRange<int>(0, 3));
  c.error = text(in.ConsumeRandomLengthString(64));
  c.wall_time_s = AnyDouble(&in);
  c.result_json = text(ResultJson(&in, lease.spec));
  std::vector<enavi_farm_EpisodeEvent> events(in.ConsumeIntegralInRange<std::size_t>(0, 3));
  for (auto& e : events) e = {AnyDouble(&in), text(in.ConsumeRandomLengthString(16)), text("")};
  c.events._length = c.events._maximum = static_cast<std::uint32_t>(events.size());
  c.events._buffer = events.empty() ? nullptr : events.data();
  std::vector<double> t, position, velocity, eci, f_per, f_col, f_dif, res, util;
  c.series.t = Doubles(&in, &t);
  c.series.position_xyz = Doubles(&in, &position);
  c.series.velocity_xyz = Doubles(&in, &velocity);
  c.series.eci = Doubles(&in, &eci);
  c.series.f_per = Doubles(&in, &f_per);
  c.series.f_col = Doubles(&in, &f_col);
  c.series.f_dif = Doubles(&in, &f_dif);
  c.series.res = Doubles(&in, &res);
  c.series.utilisation = Doubles(&in, &util);

  api::ResultMessage m;
  try {
    m = api::ResultFromSample(c);
  } catch (const std::exception&) {
    store.jobs().CancelJob(job, kNow);
    return 0;  // the bus counts it as a bad sample of its topic and drops it
  }
  const server::IngestOutcome out = store.ingest().Ingest({m}, kNow)[0];
  const nlohmann::json stored = store.queries().Results(job);
  store.jobs().CancelJob(job, kNow);  // a re-queued episode must not be the next input's lease
  if (out.ack == api::AckStatus::kStored) {
    fuzz::Check(m.episode_id == lease.episode_id, "stored a result under another episode id");
    fuzz::Check(m.status == api::ResultStatus::kOk, "stored a result that is not ok");
    fuzz::Check(api::ResultError(m.result, lease.spec).empty(), "stored a result that fails validation");
    fuzz::Check(std::isfinite(m.wall_time_s), "stored a non-finite wall time");
    fuzz::Check(stored.size() == 1, "stored, but not one result row");
  } else {
    fuzz::Check(stored.empty(), "a refused result left a row");
    fuzz::Check(!out.detail.empty(), "refused without a reason");
  }
  return 0;
}
