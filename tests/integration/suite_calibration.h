#pragma once
// The host calibration an emulated-clock suite flies with: the stored one (`enavi calibrate`)
// when it is valid on this host, else one the suite makes (a fresh machine, as in CI) with the
// calibration's flight plan at `seconds` a flight, into a directory it owns and removes.

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "workers/board/calibration_flights.h"
#include "workers/board/host_calibration.h"

namespace enavi::integration {

struct SuiteCalibration {
  std::string path;                ///< the calibration file
  std::filesystem::path own_dir;   ///< made for it (empty: the stored one is used)

  /// `tag` names the suite's directory. Call only where the emulated clock can run (root, cgroups).
  static SuiteCalibration Make(const std::string& tag, double seconds = 5.0) {
    SuiteCalibration c;
    const board::CalibrationCheck stored = board::CheckHostCalibration(board::CalibrationPath());
    if (stored.ok()) {
      c.path = stored.path;
      return c;
    }
    std::printf("no valid stored calibration (%s): calibrating this host, %.0f s flights\n", stored.message.c_str(),
                seconds);
    board::CalibrationOptions options;
    options.episode_seconds = seconds;
    const board::CalibrationRun run = board::RunCalibration(options);
    c.own_dir = std::filesystem::temp_directory_path() / ("enavi-" + tag + "-" + std::to_string(getpid()));
    std::filesystem::create_directories(c.own_dir);
    c.path = (c.own_dir / "calibration.json").string();
    board::SaveHostCalibration(run.host, c.path);
    std::printf("host speed %.3f x the reference core (%d jobs, R^2 %.3f)\n", run.relative_speed, run.fit.samples,
                run.fit.r2);
    return c;
  }
  /// Removes what Make() made.
  void Remove() {
    if (!own_dir.empty()) std::filesystem::remove_all(own_dir);
    own_dir.clear();
  }
};

}  // namespace enavi::integration
