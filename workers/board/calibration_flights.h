#pragma once
// `enavi calibrate`'s work (docs/design.md, "Time: two clocks"): fly the calibration plan on this
// host with every job's host CPU time measured, fit the cost model to it, and derive this host's
// speed against the reference core. The CLI only parses flags and prints.

#include <functional>
#include <string>
#include <vector>

#include "workers/board/calibration.h"
#include "workers/board/host_calibration.h"

namespace enavi::board {

/// One calibration flight: a method on a world, at a map resolution (0: the method's own).
struct CalibrationFlight {
  std::string method;
  std::string world;
  double resolution = 0;
  double f_dif = 0;  ///< difference detection rate (fixed only; 0 = off)
};

/// The flights `enavi calibrate` makes: a mix of scenes and resolutions so that every unit of
/// work varies independently enough to fit.
std::vector<CalibrationFlight> CalibrationPlan();

struct CalibrationOptions {
  double episode_seconds = 15.0;  ///< sim seconds per flight
  /// Called before each flight (progress output).
  std::function<void(const CalibrationFlight&)> on_flight;
};

struct CalibrationRun {
  std::vector<JobSample> samples;
  CostFit fit;                ///< reference_cpu and calibration_id filled in for this host
  ReferenceCosts reference;   ///< the embedded reference the speed was measured against
  double relative_speed = 0;  ///< this host's core vs the reference core
  HostCalibration host;       ///< what the host calibration file stores
};

/// Flies the plan and fits. Throws if the fit cannot be made (too few samples).
CalibrationRun RunCalibration(const CalibrationOptions& options);

/// Writes `costs` as a reference costs file (workers/board/profiles/reference_costs.yaml) with a
/// header comment saying where and how it was fitted plus `note`. Throws std::runtime_error if
/// the file cannot be written.
void WriteReferenceCosts(const std::string& path, const CostFit& fit, const std::string& note);

}  // namespace enavi::board
