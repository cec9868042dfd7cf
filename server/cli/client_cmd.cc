// enavi submit | status | results | cancel: clients of the farm server's HTTP API.
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>

#include "api/client.h"
#include "api/job_spec.h"
#include "server/cli/commands.h"
#include "server/eval/progress_pacer.h"
#include "server/eval/tables.h"
#include "workers/sim/episode_config.h"

namespace enavi::cli {
namespace {

struct ClientFlags {
  std::string server = api::DefaultServerUrl();
  std::string token;
};

void AddClientFlags(CLI::App* sub, ClientFlags* f) {
  sub->add_option("--server", f->server, "farm server URL")
      ->envname("ENAVI_SERVER")
      ->capture_default_str();
  sub->add_option("--token", f->token, "token for state-changing requests")->envname("ENAVI_TOKEN");
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ":1: file: cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

struct SubmitFlags {
  ClientFlags client;
  std::string file;
  bool dry_run = false;
  std::vector<std::string> world_roots;
};

void RunSubmit(const SubmitFlags& f) {
  if (f.dry_run) {
    // Local validation against local roots: the same parser the server runs.
    api::JobSpecOptions options;
    for (const auto& r : f.world_roots) options.allowed_roots.emplace_back(r);
    options.catalog = sim::FarmCatalog();
    const api::JobSpec job = api::ParseJobSpec(ReadFile(f.file), f.file, options);
    std::cout << f.file << ": valid; " << job.MatrixSize() << " episodes (";
    if (job.episodes.empty()) {
      std::cout << job.boards.size() << " boards x " << job.scenarios.size() << " scenarios x "
                << job.methods.size() << " methods x " << job.seeds.size() << " seeds)\n";
    } else {
      std::cout << job.episodes.size() << " listed x " << job.methods.size() << " methods)\n";
    }
    return;
  }
  api::FarmClient client(f.client.server, f.client.token);
  const auto submitted = client.Submit(ReadFile(f.file), f.file);
  std::cerr << "submitted '" << submitted.name << "': " << submitted.episodes << " episodes\n";
  std::cout << submitted.job_id << "\n";
}

struct StatusFlags {
  ClientFlags client;
  std::string job;
  bool watch = false;
  std::vector<std::string> labels;
};

std::string LabelText(const std::map<std::string, std::string>& labels) {
  std::string out;
  for (const auto& [k, v] : labels) out += (out.empty() ? "" : " ") + k + "=" + v;
  return out;
}

void RunStatus(const StatusFlags& f) {
  api::FarmClient client(f.client.server, f.client.token);
  const bool tty = isatty(STDOUT_FILENO) == 1;
  if (f.job.empty()) {
    std::map<std::string, std::string> filter;
    for (const auto& l : f.labels) filter.insert(api::ParseLabelFilter(l, "--label"));
    const auto jobs = client.Jobs(filter);
    if (jobs.empty()) std::cout << (filter.empty() ? "no jobs\n" : "no jobs with these labels\n");
    for (const auto& p : jobs) {
      std::cout << server::ProgressLine(p, false) << "  " << p.name;
      if (!p.labels.empty()) std::cout << "  [" << LabelText(p.labels) << "]";
      std::cout << "\n";
    }
    return;
  }
  if (!f.labels.empty()) throw std::invalid_argument("--label: filters the job list; give no JOB with it");
  server::ProgressPacer lines;
  while (true) {
    const api::JobProgress p = client.Status(f.job);
    if (tty) {
      std::cout << "\r" << server::ProgressLine(p, true) << "\033[K" << std::flush;
    } else if (!f.watch || lines.Due(p.finished(), p.total, std::chrono::steady_clock::now()) || p.terminal()) {
      std::cout << server::ProgressLine(p, false) << "\n" << std::flush;
    }
    if (!f.watch || p.terminal()) {
      if (tty) std::cout << "\n";
      for (const auto& e : p.errors) std::cout << "  failed: " << e << "\n";
      return;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

struct ResultsFlags {
  ClientFlags client;
  std::string job;
  std::string format = "table";
};

void RunResults(const ResultsFlags& f) {
  api::FarmClient client(f.client.server, f.client.token);
  const nlohmann::json results = client.Results(f.job);
  if (f.format == "json") {
    std::cout << results.dump(2) << "\n";
  } else if (f.format == "csv") {
    std::cout << server::ResultsCsv(results);
  } else {
    std::cout << server::ResultsTable(results);
  }
}

struct CancelFlags {
  ClientFlags client;
  std::string job;
};

void RunCancel(const CancelFlags& f) {
  api::FarmClient client(f.client.server, f.client.token);
  std::cout << server::ProgressLine(client.Cancel(f.job), false) << "\n";
}

}  // namespace

void RegisterClientCommands(CLI::App& app) {
  {
    auto f = std::make_shared<SubmitFlags>();
    CLI::App* sub = app.add_subcommand("submit", "Submit a job spec (YAML) to the farm server");
    sub->add_option("job", f->file, "job spec file")->required()->check(CLI::ExistingFile);
    sub->add_flag("--dry-run", f->dry_run, "validate locally and print the matrix size");
    sub->add_option("--world-root", f->world_roots,
                    "allowed root for world files in --dry-run (repeatable; default: cwd)");
    AddClientFlags(sub, &f->client);
    sub->callback([f] { RunSubmit(*f); });
  }
  {
    auto f = std::make_shared<StatusFlags>();
    CLI::App* sub = app.add_subcommand("status", "Progress of a job (or list all jobs)");
    sub->add_option("job", f->job, "job id");
    sub->add_flag("-w,--watch", f->watch, "follow until the job finishes");
    sub->add_option("--label", f->labels, "list only jobs with this label KEY=VALUE (repeatable: all must match)");
    AddClientFlags(sub, &f->client);
    sub->callback([f] { RunStatus(*f); });
  }
  {
    auto f = std::make_shared<ResultsFlags>();
    CLI::App* sub = app.add_subcommand("results", "Results of a job");
    sub->add_option("job", f->job, "job id")->required();
    sub->add_option("--format", f->format, "table, csv or json")
        ->check(CLI::IsMember({"table", "csv", "json"}))
        ->capture_default_str();
    AddClientFlags(sub, &f->client);
    sub->callback([f] { RunResults(*f); });
  }
  {
    auto f = std::make_shared<CancelFlags>();
    CLI::App* sub = app.add_subcommand("cancel", "Cancel a job: pending episodes are dropped");
    sub->add_option("job", f->job, "job id")->required();
    AddClientFlags(sub, &f->client);
    sub->callback([f] { RunCancel(*f); });
  }
}

}  // namespace enavi::cli
