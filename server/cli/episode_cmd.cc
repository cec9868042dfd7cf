// `enavi episode`: the farm worker's child command, a thin shell over sim::RunEpisodeChild.
#include "server/cli/commands.h"
#include "workers/board/calibration_flights.h"
#include "workers/emulation/emulation_options.h"
#include "workers/sim/episode_child.h"

namespace enavi::cli {

void AddSpeedProbeOption(CLI::App* app, std::string* mode) {
  app->add_option("--speed-probe", *mode,
                  "emulated clock: measure this host's speed on each CPU before the episode (~2 s of flights "
                  "a CPU) against its calibration's:\n"
                  "    use: emulate the board on the host's speed now\n"
                  "    check: report the drift (a warning beyond 10 %), keep the calibration's speed\n"
                  "    off: no probe")
      ->capture_default_str()
      ->check(CLI::IsMember({"use", "check", "off"}));
}

void ApplySpeedProbe(const std::string& mode, emulation::EmulationOptions* emulation) {
  if (mode == "off") {
    emulation->probe_host_speed = nullptr;
    return;
  }
  emulation->probe_host_speed = board::ProbeHostSpeed;
  emulation->use_probed_speed = mode == "use";
}

void RegisterEpisodeCommand(CLI::App& app) {
  struct Args {
    sim::ChildFiles files;
    std::string calibration;
    std::string speed_probe = "check";
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
  AddSpeedProbeOption(sub, &args->speed_probe);
  sub->callback([args] {
    sim::EpisodeOptions options;
    options.emulation.calibration_file = args->calibration;
    ApplySpeedProbe(args->speed_probe, &options.emulation);
    sim::RunEpisodeChild(args->files, options);
  });
}

}  // namespace enavi::cli
