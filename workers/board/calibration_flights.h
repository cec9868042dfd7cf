#pragma once
// `enavi calibrate`'s work (docs/design.md, "Time: two clocks"): fly the calibration plan on this
// host with every job's host CPU time measured, fit the cost model to it, and derive this host's
// speed against the reference core. The CLI only parses flags and prints.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "workers/board/calibration.h"
#include "workers/board/host_calibration.h"

namespace enavi::board {

/// One calibration flight: a method on a world, with overrides of its tunables.
struct CalibrationFlight {
  std::string method;
  std::string world;
  std::map<std::string, double> overrides;
};

/// The flights `enavi calibrate` makes: every registered method's own flights
/// (navstack::MethodInfo::calibration), the methods taking turns flight by flight, so that a host
/// getting busier or quieter during the run (a shared VM drifts by 10-30 % within a minute)
/// shifts every method's jobs alike instead of one method's.
std::vector<CalibrationFlight> CalibrationPlan();

struct CalibrationOptions {
  double episode_seconds = 15.0;  ///< sim seconds per flight
  /// Called before each flight (progress output).
  std::function<void(const CalibrationFlight&)> on_flight;
};

struct CalibrationRun {
  std::vector<JobSample> samples;
  FamilyFits fit;             ///< reference_cpu and calibration_id filled in for this host
  ReferenceCosts reference;   ///< the embedded reference the speed was measured against
  double relative_speed = 0;  ///< this host's core vs the reference core
  /// The reference model's price of each method's jobs against their time here (ReferenceAgreement).
  std::vector<TaskFitQuality> reference_agreement;
  HostCalibration host;       ///< what the host calibration file stores
  /// The host's 1-minute load average before the first and after the last flight (/proc/loadavg):
  /// other work on the host inflates measured job times, so a fit says what it was made under.
  double load_before = 0, load_after = 0;
};

/// Runs the speed probe (stored as the calibration's probe_speed), then flies the plan and fits.
/// Throws if the fit cannot be made (too few samples).
CalibrationRun RunCalibration(const CalibrationOptions& options);

/// The speed probe's flights: each registered method once, at its own resolution and rates (every
/// cost family), on the scenarios in turn, kSpeedProbeSeconds each.
std::vector<CalibrationFlight> SpeedProbePlan();
inline constexpr double kSpeedProbeSeconds = 2.0;

/// CPUs a probe measures at most (the first of the calling thread's affinity set): each costs
/// one run of the probe plan, ~1.8 s here.
inline constexpr int kMaxProbedCpus = 4;

/// Flies the probe plan in this process on each CPU the calling thread may run on (pinned to one
/// at a time, at most kMaxProbedCpus; the affinity is restored), every job's CPU time measured
/// and priced by the embedded reference: the host's speed now, per CPU. An emulated episode
/// compares the mean with the probe its calibration stored (DriftSinceCalibration).
SpeedProbe ProbeHostSpeed();

/// Writes the run's fit as a reference costs file (workers/board/profiles/reference_costs.yaml)
/// with a header comment saying where, how and under what load it was fitted, and why any
/// coefficient is 0. The prices are scaled by the run's relative speed, i.e. expressed on the
/// core of the reference they replace: a shared host's speed drifts by tens of per cent between
/// runs, and the board profiles' speeds must not drift with it. Throws std::runtime_error if the file cannot be written.
void WriteReferenceCosts(const std::string& path, const CalibrationRun& run);

}  // namespace enavi::board
