// enavi dashboard --db FILE: the dashboard of a finished database, read-only.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include <spdlog/spdlog.h>

#include "api/atomic_file.h"
#include "server/cli/commands.h"
#include "server/cli/farm_flags.h"
#include "server/http/http_api.h"
#include "server/store/store.h"

namespace enavi::cli {
namespace {

struct DashboardFlags {
  std::string db;
  std::string http = "127.0.0.1:" + std::to_string(api::kDefaultHttpPort);
  std::string token;
  std::string ready_file;
};

void RunDashboard(const DashboardFlags& f) {
  StopSignals signals;
  SetupLogging(false);
  const auto [host, port] = ParseHostPort(f.http, "--http");
  server::StoreOptions store_options;
  store_options.read_only = true;
  server::Store store(f.db, store_options);
  server::HttpOptions http;
  http.host = host;
  http.port = port;
  http.token = f.token;
  server::HttpApi api(&store, http);
  api.Start();
  std::cerr << "enavi dashboard: " << api.url() << "/ (read-only, " << f.db << "; Ctrl-C to stop)\n";
  if (!f.ready_file.empty()) {
    api::WriteFileAtomic(f.ready_file, api.url() + "\n");
  }
  signals.Wait();
  api.Stop();
}

}  // namespace

void RegisterDashboardCommand(CLI::App& app) {
  auto f = std::make_shared<DashboardFlags>();
  CLI::App* sub = app.add_subcommand("dashboard", "Serve the dashboard of a farm database, read-only");
  sub->add_option("--db", f->db, "SQLite database of a farm (enavi serve / eval --db)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--http", f->http, "address HOST:PORT (port 0: any free port)")->capture_default_str();
  sub->add_option("--token", f->token, "token every request must carry; needed when --http is not loopback")
      ->envname("ENAVI_TOKEN");
  sub->add_option("--ready-file", f->ready_file, "write the URL here once serving");
  sub->callback([f] { RunDashboard(*f); });
}

}  // namespace enavi::cli
