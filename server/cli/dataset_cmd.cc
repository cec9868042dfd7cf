// `enavi dataset export JOB --out DIR`: a collection job's transitions as .npz shards.
#include <cstdio>
#include <memory>

#include "api/client.h"
#include "server/cli/commands.h"
#include "server/dataset/export.h"

namespace enavi::cli {

void RegisterDatasetCommands(CLI::App& app) {
  CLI::App* dataset = app.add_subcommand("dataset", "Datasets of collection jobs (RL rollouts)");
  dataset->require_subcommand(1);
  struct Flags {
    std::string server = api::DefaultServerUrl();
    std::string token;
    dataset::ExportOptions options;
    std::string out;
  };
  auto f = std::make_shared<Flags>();
  CLI::App* cmd = dataset->add_subcommand(
      "export", "Write a collection job's transitions as NumPy .npz shards and schema.json (docs/rl.md)");
  cmd->add_option("job", f->options.job_id, "job id (a job with collect: rollouts)")->required();
  cmd->add_option("--out", f->out, "output directory")->required();
  cmd->add_option("--shard-steps", f->options.shard_steps,
                  "transitions per shard, whole episodes (default " + std::to_string(dataset::kFrequencyShardSteps) +
                      ", or " + std::to_string(dataset::kNavShardSteps) + " for the learned method's depth images)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--server", f->server, "farm server URL")->envname("ENAVI_SERVER")->capture_default_str();
  cmd->add_option("--token", f->token, "token")->envname("ENAVI_TOKEN");
  cmd->callback([f] {
    api::FarmClient client(f->server, f->token);
    f->options.out = f->out;
    const auto summary = dataset::ExportDataset(client.Rollouts(f->options.job_id), f->options);
    std::printf("%s: %d episodes, %zu transitions in %zu shards, schema %s/schema.json\n",
                f->options.job_id.c_str(), summary.episodes, summary.steps, summary.shards.size(),
                f->out.c_str());
  });
}

}  // namespace enavi::cli
