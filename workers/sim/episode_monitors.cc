#include "workers/sim/episode_monitors.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "api/fixed.h"
#include "workers/sim/episode.h"

namespace enavi::sim {
namespace {

using navstack::TaskId;

api::Vec3 ToVec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

double NavBusySeconds(const NavAccounting& acc) {
  double busy = 0;
  if (!acc.process_cpu_board_s.empty()) {
    for (const auto& [name, board_s] : acc.process_cpu_board_s) busy += board_s;
    return busy;
  }
  for (int i = 0; i < navstack::kTaskCount; ++i)
    if (navstack::IsNavigationTask(static_cast<TaskId>(i))) busy += acc.tasks[i].busy_s;
  return busy;
}

// --- eci -------------------------------------------------------------------------------------

void EciMeter::OnFrame(const FrameView& f, double board_s) {
  const double eci = f.eci.eci;
  ++frames_;
  board_s_ += board_s;
  sum_ += eci;
  min_ = std::min(min_, eci);
  max_ = std::max(max_, eci);
  took_off_ = took_off_ || f.vehicle.v_WB.norm() > FlightRecorder::kMovingSpeed;
  if (took_off_) {
    ++flight_frames_;
    flight_min_ = std::min(flight_min_, eci);
    flight_max_ = std::max(flight_max_, eci);
  }
  if (observer_) {
    const double up = std::clamp(f.frame.X_WC.linear().col(2).z(), -1.0, 1.0);  // optical axis, world z
    observer_({f.frame.t, f.eci, f.vehicle.v_WB.norm(), std::asin(up) * 180.0 / std::numbers::pi, took_off_});
  }
}

void EciMeter::Write(const EpisodeTotals& totals, api::EpisodeResult* r) const {
  r->eci = {frames_ > 0 ? min_ : 0.0, frames_ > 0 ? sum_ / frames_ : 0.0, max_,
            flight_frames_ > 0 ? flight_min_ : 0.0, flight_max_, flight_frames_};
  // E-Navi runs the eci on the board (a task); for the others it is what it would cost there.
  const navstack::TaskStats& eci_task = totals.accounting[TaskId::kEci];
  r->eci_time_ms_mean = eci_task.started > 0 ? 1e3 * eci_task.MeanCost() : frames_ > 0 ? 1e3 * board_s_ / frames_ : 0.0;
}

// --- events ----------------------------------------------------------------------------------

void EventLog::OnEvents(std::span<const navstack::NavEvent> events) {
  for (const navstack::NavEvent& e : events) {
    if (e.kind == "replan") {
      ++replans_;
      ++replans_by_trigger_[e.detail.empty() ? "unspecified" : e.detail];
    }
    if (e.kind == "emergency_stop") ++emergency_stops_;
    if (events_.size() < kMaxEvents) events_.push_back({e.t, e.kind, e.detail});
  }
}

void EventLog::Write(const EpisodeTotals&, api::EpisodeResult* r) const {
  r->replans = replans_;
  r->replans_by_trigger = replans_by_trigger_;
  r->emergency_stops = emergency_stops_;
  r->events.insert(r->events.end(), events_.begin(), events_.end());
}

// --- flight ----------------------------------------------------------------------------------

void FlightMetrics::OnStep(const StepView& s) {
  if (s.k % every_ == 0) recorder_.Sample(s.vehicle.p_WB, s.vehicle.v_WB, s.p_ref);
}

void FlightMetrics::Write(const EpisodeTotals&, api::EpisodeResult* r) const {
  r->path_length_m = recorder_.path_length();
  r->velocity_mean_mps = recorder_.speed_mean();
  r->velocity_std_mps = recorder_.speed_std();
  r->accel_peak_mps2 = recorder_.accel_peak();
  r->time_stopped_s = recorder_.time_stopped();
  r->setpoint_lag_p95_m = recorder_.setpoint_lag_p95();
}

// --- time series -----------------------------------------------------------------------------

void SeriesSampler::OnEvents(std::span<const navstack::NavEvent> events) {
  for (const navstack::NavEvent& e : events) interval_events_ += (interval_events_.empty() ? "" : ";") + e.kind;
}

void SeriesSampler::OnStep(const StepView& s) {
  if (s.k % every_ != 0) return;
  const double busy = NavBusySeconds(s.link.Accounting());
  series_.t.push_back(s.t);
  series_.position.push_back(ToVec3(s.vehicle.p_WB));
  series_.velocity.push_back(ToVec3(s.vehicle.v_WB));
  series_.eci.push_back(eci_latest_);
  const navstack::TaskRates r = s.link.rates();
  series_.f_per.push_back(r.f_per);
  series_.f_col.push_back(r.collision_on_map_update ? r.f_per : r.f_col);
  series_.f_dif.push_back(r.f_dif);
  series_.res.push_back(s.link.map_resolution());
  series_.utilisation.push_back(s.k == 0 ? 0.0 : 100.0 * (busy - last_busy_) / dt_);
  last_busy_ = busy;
  series_.events.push_back(std::exchange(interval_events_, {}));
  if (s.air_W) series_.wind_speed.push_back(s.air_W->norm());
  if (s.estimate) series_.odometry_error.push_back((s.estimate->p_WB - s.vehicle.p_WB).norm());
}

// --- CPU -------------------------------------------------------------------------------------

void CpuAccounting::Write(const EpisodeTotals& totals, api::EpisodeResult* r) const {
  const NavAccounting& acc = totals.accounting;
  const double T = totals.T;
  r->plan_failures = acc.plan_failures;
  auto util = [&](TaskId id) { return T > 0 ? 100.0 * acc[id].busy_s / T : 0.0; };
  // Each navigation task's share under the method's key for it, their sum in task order.
  double tasks_sum = 0;
  for (const TaskId id : {TaskId::kPerception, TaskId::kPlanning, TaskId::kCollision, TaskId::kDifference}) {
    const std::string key = method_ ? method_->task_keys[static_cast<int>(id)] : std::string(navstack::TaskName(id));
    r->task_cpu_util_pct[key] = util(id);
    tasks_sum += util(id);
  }
  r->nav_cpu_util_pct = acc.process_cpu_board_s.empty() ? tasks_sum : (T > 0 ? 100.0 * NavBusySeconds(acc) / T : 0.0);
  for (const auto& [name, board_s] : acc.process_cpu_board_s)
    r->notes["process." + name] = api::Fixed(T > 0 ? 100.0 * board_s / T : 0.0, 2) + " % of a board core";
  for (int i = 0; i < navstack::kTaskCount; ++i) {
    const auto id = static_cast<TaskId>(i);
    if (!navstack::IsNavigationTask(id)) continue;
    const navstack::TaskStats& st = acc[id];
    r->jobs_released += st.released;
    r->deadline_misses += st.misses();
    if (!method_) continue;  // a stack of its own processes: no tasks of ours
    const std::string& label = method_->task_labels[i];
    if (label != navstack::TaskName(id)) r->notes["task." + std::string(navstack::TaskName(id)) + ".is"] = label;
    r->notes["task." + std::string(navstack::TaskName(id))] =
        "released " + std::to_string(st.released) + ", late " + std::to_string(st.late) + ", skipped " +
        std::to_string(st.skipped) + ", mean job " + std::to_string(1e3 * st.MeanCost()) + " ms, max " +
        std::to_string(1e3 * st.cost_max_s) + " ms";
  }
  r->deadline_miss_ratio = r->jobs_released > 0 ? static_cast<double>(r->deadline_misses) / r->jobs_released : 0.0;
  r->adapter_time_ms_mean = 1e3 * acc[TaskId::kAdapter].MeanCost();
}

// --- progress --------------------------------------------------------------------------------

void ProgressReport::OnStep(const StepView& s) {
  if (s.t < next_) return;
  next_ += 1.0;
  report_(s.t, (s.vehicle.p_WB - goal_).norm());
}

std::vector<std::unique_ptr<EpisodeMonitor>> EpisodeMonitors(const EpisodeModel& model) {
  std::vector<std::unique_ptr<EpisodeMonitor>> monitors;
  monitors.push_back(std::make_unique<EciMeter>(model.options.eci_observer));
  monitors.push_back(std::make_unique<EventLog>());
  monitors.push_back(std::make_unique<FlightMetrics>(model.record_every, model.options.physics_dt));
  monitors.push_back(std::make_unique<SeriesSampler>(model.series_every, model.options.series_dt));
  monitors.push_back(std::make_unique<CpuAccounting>(model.config.method));
  if (model.options.progress)
    monitors.push_back(std::make_unique<ProgressReport>(model.options.progress, model.world->world.goal));
  return monitors;
}

}  // namespace enavi::sim
