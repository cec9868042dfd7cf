#pragma once
// The monitors every episode runs (episode_monitor.h): the eci of every frame, the stack's
// events, the flight recorder, the time series, the board's CPU accounting and the progress
// report. Each keeps its own state and writes its own fields of the result.

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "workers/sim/episode_monitor.h"
#include "workers/sim/flight_recorder.h"

namespace enavi::sim {

struct EciFrame;
struct EpisodeModel;

/// Navigation busy time, board s: the navigation tasks' (IsNavigationTask), or every process of a
/// stack that runs as processes (the paper's figure is the planner process's CPU).
double NavBusySeconds(const NavAccounting& accounting);

/// The eci of every frame: min, mean and max over the episode and over the flight (from the
/// first frame at take-off speed on), and what computing it costs on the board.
class EciMeter final : public EpisodeMonitor {
 public:
  explicit EciMeter(std::function<void(const EciFrame&)> observer = {}) : observer_(std::move(observer)) {}
  void OnFrame(const FrameView& frame, double board_s) override;
  void Write(const EpisodeTotals& totals, api::EpisodeResult* result) const override;

 private:
  std::function<void(const EciFrame&)> observer_;
  std::int64_t frames_ = 0;
  double sum_ = 0, min_ = std::numeric_limits<double>::infinity(), max_ = 0;
  bool took_off_ = false;
  std::int64_t flight_frames_ = 0;
  double flight_min_ = std::numeric_limits<double>::infinity(), flight_max_ = 0;
  double board_s_ = 0;
};

/// The stack's events: replans by trigger, emergency stops, and the first 5000 events.
class EventLog final : public EpisodeMonitor {
 public:
  void OnEvents(std::span<const navstack::NavEvent> events) override;
  void Write(const EpisodeTotals& totals, api::EpisodeResult* result) const override;

 private:
  static constexpr std::size_t kMaxEvents = 5000;
  std::int64_t replans_ = 0, emergency_stops_ = 0;
  std::map<std::string, std::int64_t> replans_by_trigger_;
  std::vector<api::EpisodeEvent> events_;
};

/// Path, speed, acceleration, stops and setpoint lag from the vehicle sampled every
/// `every` steps (FlightRecorder).
class FlightMetrics final : public EpisodeMonitor {
 public:
  FlightMetrics(long every, double physics_dt) : every_(every), recorder_(every * physics_dt) {}
  void OnStep(const StepView& step) override;
  void Write(const EpisodeTotals& totals, api::EpisodeResult* result) const override;

 private:
  long every_;
  FlightRecorder recorder_;
};

/// The time series for plots, one sample every `every` steps: position, velocity, eci of the
/// latest frame, task rates, map resolution, navigation utilisation over the interval and the
/// kinds of the events in it.
class SeriesSampler final : public EpisodeMonitor {
 public:
  SeriesSampler(long every, double dt) : every_(every), dt_(dt) {}
  void OnFrame(const FrameView& frame, double board_s) override { eci_latest_ = frame.eci.eci; }
  void OnEvents(std::span<const navstack::NavEvent> events) override;
  void OnStep(const StepView& step) override;
  void Write(const EpisodeTotals& totals, api::EpisodeResult* result) const override { result->series = series_; }

 private:
  long every_;
  double dt_;
  double eci_latest_ = 0, last_busy_ = 0;
  std::string interval_events_;
  api::TimeSeries series_;
};

/// The board's CPU: per-task utilisation, navigation CPU, releases and deadline misses, the
/// per-task notes, the adapter's mean job, per-process CPU of a stack of processes.
class CpuAccounting final : public EpisodeMonitor {
 public:
  explicit CpuAccounting(const navstack::MethodInfo* method) : method_(method) {}
  void Write(const EpisodeTotals& totals, api::EpisodeResult* result) const override;

 private:
  const navstack::MethodInfo* method_;  ///< null for a stack of its own processes
};

/// Calls `report` about once per simulated second with the distance to the goal.
class ProgressReport final : public EpisodeMonitor {
 public:
  ProgressReport(std::function<void(double, double)> report, const Eigen::Vector3d& goal)
      : report_(std::move(report)), goal_(goal) {}
  void OnStep(const StepView& step) override;

 private:
  std::function<void(double, double)> report_;
  Eigen::Vector3d goal_;
  double next_ = 1.0;
};

/// The monitors of an episode of `model`, in the order they see each step.
std::vector<std::unique_ptr<EpisodeMonitor>> EpisodeMonitors(const EpisodeModel& model);

}  // namespace enavi::sim
