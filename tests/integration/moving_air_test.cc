// The air and the odometry of issue "worlds that move", flown end to end on the virtual clock:
// turbulence and noisy odometry are deterministic per seed, the controller feels the wind (the
// tracking error grows with the turbulence's severity), the stack is told the noisy estimate and
// the metrics keep the truth.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"

namespace enavi::integration {
namespace {

api::EpisodeSpec WindySpec(std::uint64_t seed, const std::string& turbulence) {
  api::EpisodeSpec spec = Spec("s2", seed);
  spec.board = "tx2";
  spec.method = "enavi";
  spec.wind.turbulence = turbulence;
  return spec;
}

TEST(MovingAirTest, SevereTurbulenceFliesTwiceByteIdentically) {
  api::EpisodeSpec spec = WindySpec(1, "severe");
  spec.wind.speed_mps = 3.0;
  spec.wind.direction_deg = 90.0;
  spec.wind.gust = {.start_s = 5.0, .rise_s = 1.0, .hold_s = 1.0, .speed_mps = 4.0, .direction_deg = 0.0};
  spec.timeout_s = 15.0;
  const api::EpisodeResult a = sim::RunEpisode(spec), b = sim::RunEpisode(spec);
  ASSERT_EQ(a.series.wind_speed.size(), a.series.size()) << Describe(a);
  EXPECT_EQ(nlohmann::json(a).dump(), nlohmann::json(b).dump());
  // The air moved: the series holds more than the mean wind, and the gust shows around 5-7 s.
  double lo = 1e9, hi = 0;
  for (double w : a.series.wind_speed) lo = std::min(lo, w), hi = std::max(hi, w);
  EXPECT_GT(hi - lo, 1.0) << "turbulence did not vary the air";
  // Another seed is other turbulence.
  api::EpisodeSpec other = spec;
  other.seed = 2;
  EXPECT_NE(sim::RunEpisode(other).series.wind_speed, a.series.wind_speed);
}

TEST(MovingAirTest, TrackingErrorOverFiveSeedsGrowsFromStillAirToLightToSevere) {
  double mean[3] = {0, 0, 0};
  const char* levels[3] = {"none", "light", "severe"};
  for (int l = 0; l < 3; ++l) {
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      const api::EpisodeResult r = sim::RunEpisode(WindySpec(seed, levels[l]));
      EXPECT_EQ(r.series.wind_speed.empty(), l == 0) << Describe(r);
      mean[l] += r.setpoint_lag_p95_m / 5.0;
    }
    std::printf("%s: mean p95 tracking error %.3f m\n", levels[l], mean[l]);
  }
  EXPECT_GT(mean[1], mean[0]);
  EXPECT_GT(mean[2], mean[1]);
}

TEST(MovingAirTest, NoisyOdometryIsDeterministicAndTheMetricsKeepTheTruth) {
  api::EpisodeSpec spec = Spec("s3", 1);
  spec.odometry_noise = "poor";
  spec.timeout_s = 10.0;
  const api::EpisodeResult a = sim::RunEpisode(spec), b = sim::RunEpisode(spec);
  EXPECT_EQ(nlohmann::json(a).dump(), nlohmann::json(b).dump());
  ASSERT_EQ(a.series.odometry_error.size(), a.series.size()) << Describe(a);
  EXPECT_TRUE(a.series.wind_speed.empty());
  // The stack was told an estimate off the truth from the first sample on (the white noise),
  // drifting further as it flew...
  EXPECT_GT(a.series.odometry_error.front(), 0.0) << Describe(a);
  EXPECT_GT(a.series.odometry_error.back(), 0.01) << Describe(a);
  // ...while the recorded path is the truth: it starts exactly at the world's start, as the flight
  // with perfect odometry does, and that flight's series has no odometry column.
  spec.odometry_noise = "none";
  const api::EpisodeResult truth = sim::RunEpisode(spec);
  EXPECT_TRUE(truth.series.odometry_error.empty());
  EXPECT_EQ(a.series.position.front(), truth.series.position.front());
}

}  // namespace
}  // namespace enavi::integration
