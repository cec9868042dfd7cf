// `enavi episode`: the farm worker's child command, a thin shell over sim::RunEpisodeChild.
#include "server/cli/commands.h"
#include "workers/board/calibration_flights.h"
#include "workers/sim/episode_child.h"

namespace enavi::cli {

void RegisterEpisodeCommand(CLI::App& app) {
  struct Args {
    sim::ChildFiles files;
    std::string calibration;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "episode", "Fly the episode of a spec file and write its result file: what a farm worker runs for each episode");
  sub->add_option("--spec-file", args->files.spec_file, "the episode spec (one JSON object of EpisodeSpec fields)")
      ->required();
  sub->add_option("--result-file", args->files.result_file, "write the full result (JSON) here")->required();
  sub->add_option("--rollout-file", args->files.rollout_file, "E-Navi: write the training rollout here");
  sub->add_option("--calibration", args->calibration,
                  "emulated clock: host calibration file (default: $ENAVI_CALIBRATION, else the stored one)");
  sub->callback([args] {
    sim::EpisodeOptions options;
    options.emulation.calibration_file = args->calibration;
    options.emulation.probe_host_speed = board::ProbeHostSpeed;  // the spec's speed_probe says what for
    // A worker's emulated episodes take turns for the host's CPUs (its other slots, other workers).
    options.emulation.admission_wait_s = 600;
    sim::RunEpisodeChild(args->files, options);
  });
}

}  // namespace enavi::cli
