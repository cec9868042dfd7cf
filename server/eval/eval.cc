#include "server/eval/eval.h"

#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include <spdlog/spdlog.h>

#include "api/dds_config.h"
#include "server/eval/tables.h"
#include "server/scheduler/farm_server.h"
#include "server/store/store.h"
#include "workers/worker/process.h"

namespace enavi::server {
namespace {

namespace fs = std::filesystem;

std::string YamlList(const std::vector<std::string>& items) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += (i ? ", " : "") + std::string("\"") + items[i] + "\"";
  }
  return out + "]";
}

// A private directory for the temporary database, spools and logs; removed on destruction
// unless asked to keep it.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "enavi-eval-XXXXXX").string();
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

std::string LogTail(const fs::path& file) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.size() > 1500) text = "..." + text.substr(text.size() - 1500);
  return text;
}

}  // namespace

std::string EvalJobYaml(const EvalOptions& o) {
  std::ostringstream y;
  y << "name: eval\n"
    << "boards: " << YamlList(o.boards) << "\n"
    << "scenarios: " << YamlList(o.scenarios) << "\n"
    << "methods: " << YamlList(o.methods) << "\n"
    << "seeds: " << o.seeds << "\n"
    << "clock: \"" << o.clock << "\"\n"
    << "cost: \"" << o.cost << "\"\n";
  return y.str();
}

EvalReport RunEval(const EvalOptions& options, std::ostream& progress_out) {
  if (options.workers < 1 || options.workers > 64) {
    throw std::invalid_argument("--workers: " + std::to_string(options.workers) + " outside [1, 64]");
  }
  if (options.slots < 1 || options.slots > 64) {
    throw std::invalid_argument("--slots: " + std::to_string(options.slots) + " outside [1, 64]");
  }
  // Validate the matrix exactly as a submitted job; errors name the line of the flag.
  const std::string yaml = EvalJobYaml(options);
  const api::JobSpec job = api::ParseJobSpec(yaml, "enavi eval flags", options.job_spec);

  const fs::path enavi = options.enavi.empty() ? worker::SelfExecutable() : options.enavi;

  TempDir tmp;
  const fs::path db = options.db.empty() ? tmp.path() / "eval.db" : options.db;

  // Private farm: loopback only, a domain derived from the pid and a partition nobody else uses.
  std::random_device rd;
  api::BusOptions bus;
  bus.domain_id = options.domain.value_or(1 + static_cast<std::uint32_t>(getpid()) % 200);
  {
    std::ostringstream partition;
    partition << "eval-" << getpid() << "-" << std::hex << rd();
    bus.partition = partition.str();
  }
  api::DdsNetwork network;
  network.loopback = true;
  bus.config_xml = api::CycloneConfigXml(network);

  Store store(db);
  FarmServerOptions server_options;
  server_options.bus = bus;
  FarmServer farm(&store, server_options);
  farm.Start();
  std::unique_ptr<HttpApi> http;
  if (options.dashboard) {
    http = std::make_unique<HttpApi>(&farm, *options.dashboard);
    http->Start();
    progress_out << "dashboard: " << http->url() << "/\n" << std::flush;
  }

  // Workers: separate processes running `enavi worker`, as on a cluster.
  std::vector<worker::ChildProcess> workers;
  std::vector<fs::path> logs;
  for (int i = 0; i < options.workers; ++i) {
    const fs::path dir = tmp.path() / ("worker-" + std::to_string(i));
    fs::create_directories(dir);
    worker::SpawnOptions spawn;
    spawn.argv = {enavi.string(), "worker", "--domain", std::to_string(bus.domain_id),
                  "--partition", bus.partition, "--loopback", "--slots",
                  std::to_string(options.slots), "--id",
                  "eval-" + std::to_string(getpid()) + "-w" + std::to_string(i), "--spool",
                  (dir / "spool").string(), "--work-dir", (dir / "work").string(),
                  "--episode-timeout", std::to_string(options.episode_timeout.count())};
    if (!options.episode_command.empty()) {
      spawn.argv.insert(spawn.argv.end(), {"--episode-cmd", options.episode_command});
    }
    spawn.stdout_file = dir / "worker.log";
    spawn.stderr_file = dir / "worker.log";
    logs.push_back(dir / "worker.log");
    workers.push_back(worker::ChildProcess::Spawn(spawn));
  }

  EvalReport report;
  report.job_id = farm.Submit(job, yaml);
  auto last_print = std::chrono::steady_clock::time_point{};
  while (true) {
    report.progress = *store.Progress(report.job_id, NowMs());
    const auto now = std::chrono::steady_clock::now();
    // A bar redrawn in place on a terminal; piped, only the final line (DESIGN.md section 10).
    if (report.progress.terminal() ||
        (options.progress_bar && now - last_print >= options.progress_period)) {
      const std::string line = ProgressLine(report.progress, options.progress_bar);
      if (options.progress_bar) {
        progress_out << "\r" << line << "\033[K" << std::flush;
      } else {
        progress_out << line << "\n" << std::flush;
      }
      last_print = now;
    }
    if (report.progress.terminal()) break;
    int alive = 0;
    for (auto& w : workers) alive += w.Poll() ? 0 : 1;
    if (alive == 0) {
      tmp.Keep();
      throw std::runtime_error("every eval worker exited; last log lines of " + logs.front().string() +
                               ":\n" + LogTail(logs.front()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (options.progress_bar) progress_out << "\n";

  // Graceful stop: workers drain (nothing runs now) and leave; then the server.
  for (auto& w : workers) w.Signal(SIGTERM);
  for (auto& w : workers) {
    if (!w.Wait(std::chrono::seconds(15))) w.Terminate(std::chrono::seconds(1));
  }
  report.results = store.Results(report.job_id);
  if (http && options.while_serving) options.while_serving(report);
  if (http) http->Stop();
  farm.Stop();
  return report;
}

}  // namespace enavi::server
