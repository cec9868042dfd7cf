#include "server/eval/local_farm.h"

#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "api/dds_config.h"
#include "server/http/http_api.h"
#include "server/scheduler/farm_server.h"
#include "server/store/store.h"
#include "workers/worker/process.h"

namespace enavi::server {

namespace fs = std::filesystem;

// A private directory for the temporary database, spools and logs; removed on destruction
// unless asked to keep it. Not in the anonymous namespace: LocalFarm::Impl, which has linkage,
// holds one.
namespace local_farm_detail {
class TempDir {
 public:
  explicit TempDir(const std::string& name) {
    std::string pattern = (fs::temp_directory_path() / ("enavi-" + name + "-XXXXXX")).string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot create a temp dir");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    if (!keep_) fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  void Keep() { keep_ = true; }

 private:
  fs::path path_;
  bool keep_ = false;
};
}  // namespace local_farm_detail

namespace {

std::string LogTail(const fs::path& file) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.size() > 1500) text = "..." + text.substr(text.size() - 1500);
  return text;
}

}  // namespace

struct LocalFarm::Impl {
  explicit Impl(const LocalFarmOptions& o) : tmp(o.name) {}
  local_farm_detail::TempDir tmp;
  std::unique_ptr<Store> store;
  std::unique_ptr<FarmServer> farm;
  std::unique_ptr<HttpApi> http;
  std::vector<worker::ChildProcess> workers;
  std::vector<fs::path> logs;
  bool stopped = false;
};

LocalFarm::LocalFarm(const LocalFarmOptions& options) {
  if (options.workers < 1 || options.workers > 64) {
    throw std::invalid_argument("--workers: " + std::to_string(options.workers) + " outside [1, 64]");
  }
  if (options.slots < 1 || options.slots > 64) {
    throw std::invalid_argument("--slots: " + std::to_string(options.slots) + " outside [1, 64]");
  }
  impl_ = std::make_unique<Impl>(options);
  const fs::path enavi = options.enavi.empty() ? worker::SelfExecutable() : options.enavi;
  const fs::path db = options.db.empty() ? impl_->tmp.path() / (options.name + ".db") : options.db;

  // Private farm: loopback only, a domain derived from the pid and a partition nobody else uses.
  std::random_device rd;
  api::BusOptions bus;
  bus.domain_id = options.domain.value_or(1 + static_cast<std::uint32_t>(getpid()) % 200);
  {
    std::ostringstream partition;
    partition << options.name << "-" << getpid() << "-" << std::hex << rd();
    bus.partition = partition.str();
  }
  api::DdsNetwork network;
  network.loopback = true;
  bus.config_xml = api::CycloneConfigXml(network);

  impl_->store = std::make_unique<Store>(db);
  FarmServerOptions server_options;
  server_options.bus = bus;
  impl_->farm = std::make_unique<FarmServer>(impl_->store.get(), server_options);
  impl_->farm->Start();
  if (options.http) {
    HttpOptions http;
    http.job_spec = options.job_spec;
    impl_->http = std::make_unique<HttpApi>(impl_->farm.get(), http);
    impl_->http->Start();
  }

  // Workers: separate processes running `enavi worker`, as on a cluster.
  for (int i = 0; i < options.workers; ++i) {
    const fs::path dir = impl_->tmp.path() / ("worker-" + std::to_string(i));
    fs::create_directories(dir);
    worker::SpawnOptions spawn;
    spawn.argv = {enavi.string(), "worker", "--domain", std::to_string(bus.domain_id),
                  "--partition", bus.partition, "--loopback", "--slots",
                  std::to_string(options.slots), "--id",
                  options.name + "-" + std::to_string(getpid()) + "-w" + std::to_string(i), "--spool",
                  (dir / "spool").string(), "--work-dir", (dir / "work").string(),
                  "--episode-timeout", std::to_string(options.episode_timeout.count())};
    if (!options.episode_command.empty()) {
      spawn.argv.insert(spawn.argv.end(), {"--episode-cmd", options.episode_command});
    }
    spawn.stdout_file = dir / "worker.log";
    spawn.stderr_file = dir / "worker.log";
    impl_->logs.push_back(dir / "worker.log");
    impl_->workers.push_back(worker::ChildProcess::Spawn(spawn));
  }
}

LocalFarm::~LocalFarm() { Stop(); }

Store& LocalFarm::store() { return *impl_->store; }
FarmServer& LocalFarm::farm() { return *impl_->farm; }

std::string LocalFarm::url() const {
  if (!impl_->http) throw std::logic_error("LocalFarm: started without its HTTP API");
  return impl_->http->url();
}

void LocalFarm::CheckWorkers() {
  int alive = 0;
  for (auto& w : impl_->workers) alive += w.Poll() ? 0 : 1;
  if (alive > 0) return;
  impl_->tmp.Keep();
  throw std::runtime_error("every local worker exited; last log lines of " + impl_->logs.front().string() +
                           ":\n" + LogTail(impl_->logs.front()));
}

void LocalFarm::Stop() {
  if (!impl_ || impl_->stopped) return;
  impl_->stopped = true;
  // Graceful stop: workers drain and leave; then the HTTP API and the server.
  for (auto& w : impl_->workers) w.Signal(SIGTERM);
  for (auto& w : impl_->workers) {
    if (!w.Wait(std::chrono::seconds(15))) w.Terminate(std::chrono::seconds(1));
  }
  if (impl_->http) impl_->http->Stop();
  impl_->farm->Stop();
}

}  // namespace enavi::server
