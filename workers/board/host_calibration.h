#pragma once
// The host calibration file (docs/design.md, "Time: two clocks", `enavi calibrate`): how fast THIS machine's
// cores are relative to the reference core the board profiles are expressed against, the
// cost-model coefficients fitted here, and the worst job times seen in the calibration flights.
// The emulated clock needs it to size a board's quota (speed = board speed / host speed);
// a file written on another CPU or against another reference fit is stale and refused.
//
// Location: --calibration FILE, else $ENAVI_CALIBRATION, else
// $XDG_STATE_HOME/enavi/calibration.json, else ~/.local/state/enavi/calibration.json.

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "workers/board/board_profile.h"

namespace enavi::board {

/// Worst and typical host CPU time of one task's jobs in the calibration flights, seconds.
struct TaskTiming {
  int jobs = 0;
  double mean_s = 0;
  double p99_s = 0;
  double max_s = 0;
};

struct HostCalibration {
  /// 3: one fit per cost family; 2: one ns per job per task (older versions are refused:
  /// calibrate again).
  static constexpr int kFormatVersion = 3;
  /// This host's single-core speed relative to the reference core (> 1: faster).
  double relative_speed = 1.0;
  /// The speed probe's measure of the same (ProbeHostSpeed, just before the plan): what an
  /// emulated episode's probe is compared with. 0: not measured (a file written before the
  /// probe existed; the probe is then compared with relative_speed).
  double probe_speed = 0.0;
  /// The cost model fitted on this host, by cost family (ns per unit on THIS host's cores).
  std::map<std::string, navstack::WorkCountCostModel::Coefficients> fitted;
  int samples = 0;
  double r2 = 0;
  std::string cpu_model;  ///< /proc/cpuinfo "model name"
  std::string kernel;     ///< uname -r
  std::string date;       ///< UTC, ISO 8601
  /// calibration_id of the reference costs the speed was measured against.
  std::string reference_calibration_id;
  std::map<std::string, TaskTiming> tasks;  ///< by task name (navstack::TaskName)
};

/// Where the calibration lives: `flag` if not empty, else $ENAVI_CALIBRATION, else
/// $XDG_STATE_HOME/enavi/calibration.json, else $HOME/.local/state/enavi/calibration.json.
/// Throws std::invalid_argument if none of these can be formed (no HOME).
std::string CalibrationPath(const std::string& flag = {});

/// Writes the file (creating its directory). Throws std::runtime_error if it cannot.
void SaveHostCalibration(const HostCalibration& calibration, const std::string& path);
/// Reads the file. Throws std::invalid_argument naming the file and field if it is missing,
/// not JSON, or a field is absent or out of range.
HostCalibration LoadHostCalibration(const std::string& path);

/// The machine the process runs on, as the calibration records it.
std::string HostCpuModel();
std::string HostKernel();

/// Whether a calibration file can be used on this host.
struct CalibrationCheck {
  enum class Status { kValid, kMissing, kStale, kInvalid };
  Status status = Status::kMissing;
  std::string path;
  std::string message;  ///< for anything but kValid: what is wrong and that `enavi calibrate` fixes it
  std::optional<HostCalibration> calibration;  ///< set when the file could be read (also if stale)
  bool ok() const { return status == Status::kValid; }
};
/// Loads `path` and checks it against this machine (`cpu_model`) and the embedded reference
/// costs (`reference_calibration_id`). Never throws for a bad file: the status says why.
CalibrationCheck CheckHostCalibration(const std::string& path, const std::string& cpu_model,
                                      const std::string& reference_calibration_id);
/// The same for this machine and the embedded reference costs.
CalibrationCheck CheckHostCalibration(const std::string& path);

/// Per-core speed of `board` relative to a host whose core is `host_speed` x the reference core:
/// 1 for the host itself, else board.per_core_speed / host_speed.
double SpeedVsHost(const BoardProfile& board, double host_speed);

/// One speed probe (ProbeHostSpeed, workers/board/calibration_flights.h): this host's speed
/// against the reference core now, on each CPU the probing thread may run on. A VM's vCPUs do not
/// run at one speed: with no steal time reported to the guest, a vCPU whose physical core is
/// shared with another guest just looks slower (this VM's two: 33 % apart for minutes, then equal).
struct SpeedProbe {
  std::vector<std::pair<int, double>> per_cpu;  ///< (CPU number, speed x the reference core)
  double speed = 0;   ///< the mean over per_cpu
  int jobs = 0;       ///< jobs timed
  double wall_s = 0;  ///< how long the probe took
  /// (fastest - slowest) / slowest CPU; 0 with one CPU.
  double Spread() const;
};

/// How far this host's speed has moved since its calibration, from a speed probe run now
/// (ProbeHostSpeed, workers/board/calibration_flights.h). A shared host's speed drifts by tens of
/// per cent over hours (noisy neighbours, boost clocks), and an emulated board is exactly as fast
/// as the host speed it is divided by.
struct SpeedDrift {
  double probed = 0;       ///< the probe's speed now, x the reference core
  double at_calibration = 0;  ///< the probe's speed when the calibration was made (or relative_speed)
  double ratio = 1;        ///< probed / at_calibration
  double host_speed = 0;   ///< relative_speed x ratio: the calibration's speed moved by the drift
};
/// @throws std::invalid_argument if `probed` is not a positive finite speed.
SpeedDrift DriftSinceCalibration(const HostCalibration& host, double probed);

/// How a probe reads against a calibration, in the words of an emulated episode's note and
/// warnings and of `enavi calibrate --status --probe`.
struct DriftText {
  /// "this host's speed moved -5.1 % since its calibration (DATE; probe 1.176 x the reference core
  /// now, 1.239 then)"
  std::string drift;
  /// "its CPUs differ by 2.1 % (CPU 0 1.188, CPU 1 1.163)"
  std::string spread;
};
DriftText DescribeDrift(const HostCalibration& host, const SpeedProbe& probe);

/// Drift (|ratio - 1|) or spread between CPUs beyond which an emulated episode warns: the clock
/// agreement the project aims at between the virtual and the emulated clock is 15 %, and an error
/// of this size in the host's speed alone would use up most of it.
inline constexpr double kSpeedDriftWarning = 0.10;

/// Timing summary of a task's job times (seconds); empty input gives jobs = 0.
TaskTiming SummariseTimes(std::vector<double> seconds);

}  // namespace enavi::board
