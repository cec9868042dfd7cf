// enavi: one executable, subcommands with --help (README.md, "Commands").
#include <cstdio>
#include <exception>
#include <stdexcept>

#include <CLI/CLI.hpp>

#include "api/provenance.h"
#include "server/cli/commands.h"
#include "workers/emulation/emulated_nav_link.h"
#ifdef ENAVI_WITH_ROS
#include "workers/ros/ros_nav_link.h"
#endif

int main(int argc, char** argv) {
  using namespace enavi::cli;
  CLI::App app{"E-Navi Farm: a simulation farm for UAV navigation stacks on weak onboard computers"};
  app.set_version_flag("--version", "enavi " + enavi::api::BuildVersion() + " (commit " + enavi::api::BuildCommit() + ")",
                       "print the version and the commit it was built from");
  app.require_subcommand(1);
  // The links beyond the built-in virtual clock's, before any help text lists the clocks.
  enavi::emulation::RegisterEmulatedLink();  // --clock emulated (docs/design.md, "Time: two clocks")
#ifdef ENAVI_WITH_ROS
  enavi::ros::RegisterRosLink();  // ROS methods fly here (docs/ros.md)
#endif
  RegisterWorldCommands(app);
  RegisterFlyCommand(app);
  RegisterEpisodeCommand(app);
  RegisterBenchCommands(app);
  RegisterCalibrateCommand(app);
  RegisterTrainCommand(app);
  RegisterServeCommand(app);
  RegisterWorkerCommand(app);
  RegisterClientCommands(app);
  RegisterEvalCommand(app);
  RegisterDatasetCommands(app);
  RegisterCompareCommand(app);
  RegisterTrendCommand(app);
  RegisterDashboardCommand(app);
  RegisterPolicyCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const ExitStatus& e) {
    return e.code;
  } catch (const CLI::ParseError& e) {
    // CLI11 prints help on --help (exit 0) and usage errors (bad flags) with its own code;
    // we map every usage error to the bad-input code.
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitFailure;
  }
  return kExitOk;
}
