// The farm's HTTP API (server/http/http_api.h) without sockets: any bytes as one request go
// through HttpApi::HandleRaw (access checks, routing, handlers) of a farm server over a store
// that holds one job with one stored result. In the input, JOB_ID and EPISODE_ID stand for that
// job's and episode's ids, so the seeds reach every route. Every request gets an HTTP response;
// none is a 500 (an exception the handlers did not turn into a 4xx with a message).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include "api/dds_config.h"
#include "server/http/http_api.h"
#include "server/store/ingest.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using namespace enavi;

struct Farm {
  std::unique_ptr<server::Store> store;
  std::unique_ptr<server::FarmServer> farm;
  std::unique_ptr<server::HttpApi> http;
  std::string job_id, episode_id;
};

Farm& TheFarm() {
  static Farm f = [] {
    Farm f;
    spdlog::set_level(spdlog::level::off);
    const std::filesystem::path shm = "/dev/shm";
    const auto dir = (std::filesystem::exists(shm) ? shm : std::filesystem::temp_directory_path()) /
                     ("enavi-fuzz-http-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    f.store = std::make_unique<server::Store>(dir / "farm.db");
    // A bus of its own on loopback (never started: no loop thread, no workers).
    server::FarmServerOptions options;
    options.bus.domain_id = 200 + static_cast<std::uint32_t>(::getpid()) % 30;
    options.bus.partition = "fuzz-" + std::to_string(::getpid());
    api::DdsNetwork net;
    net.loopback = true;
    options.bus.config_xml = api::CycloneConfigXml(net);
    f.farm = std::make_unique<server::FarmServer>(f.store.get(), options);
    server::HttpOptions http;
    http.job_spec.allowed_roots = {dir};
    http.job_spec.catalog = fuzz::Catalog();
    f.http = std::make_unique<server::HttpApi>(f.farm.get(), http);
    // One job with one episode done.
    api::EpisodeSpec spec;
    spec.board = "tx2";
    spec.method = "enavi";
    f.job_id = f.store->jobs().CreateJob("seed", "boards: [tx2]", {spec}, 1000);
    const auto lease = f.store->leases().LeaseEpisodes("w1", 1, {}, 20'000, 1000).at(0);
    f.episode_id = lease.episode_id;
    api::ResultMessage m;
    m.episode_id = lease.episode_id;
    m.attempt = lease.attempt;
    m.worker_id = "w1";
    m.job_id = f.job_id;
    m.result.spec = lease.spec;
    m.result.success = true;
    m.result.flight_time_s = 10;
    m.result.series.t = {0, 0.1};
    m.result.series.position = {{0, 0, 1}, {0.1, 0, 1}};
    f.store->ingest().Ingest({m}, 2000);
    return f;
  }();
  return f;
}

void ReplaceAll(std::string* s, const std::string& from, const std::string& to) {
  for (auto at = s->find(from); at != std::string::npos; at = s->find(from, at + to.size())) s->replace(at, from.size(), to);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Farm& f = TheFarm();
  std::string request(reinterpret_cast<const char*>(data), size);
  ReplaceAll(&request, "JOB_ID", f.job_id);
  ReplaceAll(&request, "EPISODE_ID", f.episode_id);
  const std::string response = f.http->HandleRaw(request);
  // httplib answers nothing to bytes that are not a request line; anything else has a status.
  if (response.empty()) return 0;
  fuzz::Check(response.rfind("HTTP/1.1 ", 0) == 0, "response without a status line");
  if (response.compare(9, 3, "500") == 0) {
    std::fprintf(stderr, "500 for:\n%s\n--- response:\n%s\n", request.c_str(), response.c_str());
    std::abort();
  }
  return 0;
}
