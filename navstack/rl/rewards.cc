#include "navstack/rl/rewards.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack::rl {

void RewardWeights::Validate() const {
  const std::pair<const char*, double> fields[] = {
      {"w_util", w_util},         {"w_over", w_over}, {"w_progress", w_progress},
      {"w_path", w_path},         {"w_collision", w_collision},
      {"w_goal", w_goal},         {"w_time", w_time}, {"w_stop", w_stop}};
  for (const auto& [name, v] : fields) {
    if (!(v >= 0.0 && v <= 1000.0)) {
      std::ostringstream os;
      os << "reward weight " << name << " = " << v << " must be in [0, 1000]";
      throw std::invalid_argument(os.str());
    }
  }
}

nlohmann::json RewardWeightsToJson(const RewardWeights& w) {
  return {{"w_util", w.w_util},         {"w_over", w.w_over}, {"w_progress", w.w_progress},
          {"w_path", w.w_path},         {"w_collision", w.w_collision},
          {"w_goal", w.w_goal},         {"w_time", w.w_time}, {"w_stop", w.w_stop}};
}

RewardTerms ComputeReward(const RewardInputs& in, const RewardWeights& w) {
  const bool ok = in.dt >= 0.0 && in.u_nav >= 0.0 && in.u_total > 0.0 && in.dist_prev >= 0.0 &&
                  in.dist >= 0.0 && in.straight_length > 0.0 && !std::isnan(in.path_prev) &&
                  !std::isnan(in.path) && std::isfinite(in.dt) && std::isfinite(in.u_nav) &&
                  std::isfinite(in.dist_prev) && std::isfinite(in.dist) &&
                  std::isfinite(in.straight_length) && in.stops >= 0;
  if (!ok) {
    throw std::domain_error("ComputeReward: inputs must be finite with dt, u_nav, distances >= 0 "
                            "and u_total, straight_length > 0, stops >= 0");
  }
  RewardTerms r;
  // R_c: CPU as a rate, with a steep hinge above capacity.
  const double load = in.u_nav / in.u_total;
  r.utilisation = -w.w_util * load * in.dt;
  r.overload = -w.w_over * std::max(0.0, load - 1.0) * in.dt;
  r.r_c = r.utilisation + r.overload;
  // R_f: progress, path growth, terminal events, time.
  r.progress = w.w_progress * (in.dist_prev - in.dist) / in.straight_length;
  if (in.path_prev > 0.0 && in.path > 0.0) {
    r.path_growth = w.w_path * std::clamp(1.0 - in.path / in.path_prev, -1.0, 1.0);
  }
  r.collision = in.collided ? -w.w_collision : 0.0;
  r.goal = in.reached_goal ? w.w_goal : 0.0;
  r.time = -w.w_time * in.dt;
  r.stops = -w.w_stop * in.stops;
  r.r_f = r.progress + r.path_growth + r.collision + r.goal + r.time + r.stops;
  r.total = r.r_c + r.r_f;
  return r;
}

}  // namespace enavi::navstack::rl
