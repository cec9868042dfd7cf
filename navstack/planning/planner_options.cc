#include "navstack/planning/planner_options.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace enavi::navstack {
namespace {

// Range check with the field name and the allowed range in the message (STYLE.md rule 10).
void CheckRange(const char* field, double value, double lo, double hi, bool lo_open) {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
  if (ok) return;
  std::ostringstream msg;
  msg << "PlannerOptions." << field << " = " << value << ": must be in " << (lo_open ? "(" : "[")
      << lo << ", " << hi << "]";
  throw std::invalid_argument(msg.str());
}

}  // namespace

const char* ToString(PlannerOptimizer optimizer) {
  switch (optimizer) {
    case PlannerOptimizer::kEsdf: return "esdf";
    case PlannerOptimizer::kRebound: return "rebound";
  }
  return "unknown";
}

bool ParsePlannerOptimizer(std::string_view name, PlannerOptimizer* out) {
  for (PlannerOptimizer o : {PlannerOptimizer::kEsdf, PlannerOptimizer::kRebound}) {
    if (name == ToString(o)) {
      *out = o;
      return true;
    }
  }
  return false;
}

void PlannerOptions::Validate() const {
  const int opt = static_cast<int>(optimizer);
  if (opt != static_cast<int>(PlannerOptimizer::kEsdf) &&
      opt != static_cast<int>(PlannerOptimizer::kRebound)) {
    throw std::invalid_argument("PlannerOptions.optimizer = " + std::to_string(opt) +
                                ": must be 0 (esdf) or 1 (rebound)");
  }
  CheckRange("robot_radius", robot_radius, 0.0, 5.0, true);
  CheckRange("v_max", v_max, 0.0, 20.0, true);
  CheckRange("a_max", a_max, 0.0, 50.0, true);
  CheckRange("camera_range", camera_range, 1.0, 50.0, false);
  CheckRange("volume_back_margin", volume_back_margin, 0.0, 20.0, false);
  CheckRange("volume_height", volume_height, 1.0, 50.0, false);
  CheckRange("min_altitude", min_altitude, -1e4, 1e4, false);
  CheckRange("search_margin", search_margin, 0.0, 5.0, false);
  CheckRange("motion_check_fraction", motion_check_fraction, 0.0, 2.0, true);
  CheckRange("search_range", search_range, 0.0, 100.0, true);
  CheckRange("max_search_iterations", max_search_iterations, 1, 1e7, false);
  CheckRange("max_goal_candidates", max_goal_candidates, 1, 20, false);
  CheckRange("local_goal_search_radius", local_goal_search_radius, 0.0, 20.0, false);
  CheckRange("shortcut_spacing", shortcut_spacing, 0.0, 10.0, true);
  CheckRange("control_point_spacing", control_point_spacing, 0.0, 5.0, true);
  CheckRange("safe_distance_margin", safe_distance_margin, 0.0, 5.0, false);
  CheckRange("weight_smoothness", weight_smoothness, 0.0, 1e6, false);
  CheckRange("weight_clearance", weight_clearance, 0.0, 1e6, false);
  CheckRange("weight_feasibility", weight_feasibility, 0.0, 1e6, false);
  CheckRange("max_optimizer_iterations", max_optimizer_iterations, 1, 1e5, false);
  CheckRange("max_time_reallocations", max_time_reallocations, 0, 100, false);
  CheckRange("max_clearance_retries", max_clearance_retries, 0, 10, false);
  CheckRange("rebound_lambda_smooth", rebound_lambda_smooth, 0.0, 1e6, false);
  CheckRange("rebound_lambda_collision", rebound_lambda_collision, 0.0, 1e6, false);
  CheckRange("rebound_lambda_feasibility", rebound_lambda_feasibility, 0.0, 1e6, false);
  CheckRange("rebound_dist0", rebound_dist0, 0.0, 5.0, true);
  CheckRange("max_rebounds", max_rebounds, 0, 1000, false);
  CheckRange("max_rebound_restarts", max_rebound_restarts, 0, 100, false);
  CheckRange("yaw_speed_threshold", yaw_speed_threshold, 0.0, 20.0, false);
  CheckRange("yaw_rate_max", yaw_rate_max, 0.0, 100.0, true);
  CheckRange("yaw_accel_max", yaw_accel_max, 0.0, 1000.0, true);
  CheckRange("yaw_lookahead", yaw_lookahead, 0.0, 10.0, false);
}

}  // namespace enavi::navstack
