#include "workers/sim/flight_recorder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace enavi::sim {

FlightRecorder::FlightRecorder(double dt, double accel_window) : dt_(dt) {
  accel_lag_ = std::max(1, static_cast<int>(std::lround(accel_window / dt)));
  if (dt <= 0 || accel_lag_ >= kRing) throw std::logic_error("FlightRecorder: bad dt/window");
}

void FlightRecorder::Sample(const Eigen::Vector3d& p_W, const Eigen::Vector3d& v_W, const Eigen::Vector3d& p_ref_W) {
  if (n_ > 0) path_length_ += (p_W - last_p_).norm();
  last_p_ = p_W;
  const double speed = v_W.norm();
  moved_ = moved_ || speed > kMovingSpeed;
  if (moved_ && speed < kStoppedSpeed) ++stopped_samples_;
  lag_.push_back(static_cast<float>((p_ref_W - p_W).norm()));
  speed_sum_ += speed;
  speed_sq_sum_ += speed * speed;
  ring_[n_ % kRing] = v_W;
  if (n_ >= accel_lag_) {
    const Eigen::Vector3d& v_old = ring_[(n_ - accel_lag_) % kRing];
    accel_peak_ = std::max(accel_peak_, (v_W - v_old).norm() / (accel_lag_ * dt_));
  }
  ++n_;
}

double FlightRecorder::setpoint_lag_p95() const {
  if (lag_.empty()) return 0.0;
  std::vector<float> sorted = lag_;
  const std::size_t k = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(sorted.size()))) - 1;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
  return sorted[k];
}

double FlightRecorder::speed_mean() const { return n_ > 0 ? speed_sum_ / n_ : 0.0; }

double FlightRecorder::speed_std() const {
  if (n_ < 2) return 0.0;
  const double mean = speed_mean();
  return std::sqrt(std::max(0.0, speed_sq_sum_ / n_ - mean * mean));
}

}  // namespace enavi::sim
