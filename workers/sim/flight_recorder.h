#pragma once
// Flight metrics of one episode (README.md, "One flight" and api/episode.h): path length, speed statistics and peak
// acceleration, from the vehicle state sampled at a fixed rate.

#include <vector>

#include <Eigen/Core>

namespace enavi::sim {

class FlightRecorder {
 public:
  /// `dt`: the fixed interval at which Sample() is called. Peak acceleration is taken from
  /// velocity differences over `accel_window` seconds, which filters motor-lag ripple.
  explicit FlightRecorder(double dt = 0.01, double accel_window = 0.05);

  /// One sample of the vehicle and of the reference position the controller tracked.
  void Sample(const Eigen::Vector3d& p_W, const Eigen::Vector3d& v_W, const Eigen::Vector3d& p_ref_W);

  double path_length() const { return path_length_; }
  double speed_mean() const;
  double speed_std() const;
  double accel_peak() const { return accel_peak_; }
  long samples() const { return n_; }
  /// Time below kStoppedSpeed after the speed first exceeded kMovingSpeed.
  double time_stopped() const { return stopped_samples_ * dt_; }
  /// 95th percentile of the distance between reference and vehicle.
  double setpoint_lag_p95() const;

  static constexpr double kStoppedSpeed = 0.1;  ///< m/s (Ego-Planner's stop criterion)
  static constexpr double kMovingSpeed = 0.5;   ///< m/s

 private:
  double dt_;
  int accel_lag_;  ///< samples between the two velocities of one acceleration estimate
  long n_ = 0;
  Eigen::Vector3d last_p_ = Eigen::Vector3d::Zero();
  double path_length_ = 0;
  double speed_sum_ = 0, speed_sq_sum_ = 0;
  double accel_peak_ = 0;
  bool moved_ = false;
  long stopped_samples_ = 0;
  std::vector<float> lag_;
  // Ring of recent velocities for the windowed acceleration estimate.
  static constexpr int kRing = 64;
  Eigen::Vector3d ring_[kRing];
};

}  // namespace enavi::sim
