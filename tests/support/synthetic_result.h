#pragma once
// A synthetic but schema-valid flight result derived only from its spec (so it is
// deterministic): what tests/system/fake_episode answers, and what the dashboard's browser test
// and benchmark seed their databases with. Real episodes take ~20 s of CPU each.
//
// Flights cruise at a nominal 2 m/s: a `planner.v_max` override below that stretches the flight
// time by 2 / v_max (a slower flight, as the real planner's would be). A seed divisible by 7
// collides; `fake.deadline_misses` sets the deadline misses.

#include "api/episode.h"

namespace enavi::testing {

/// @param series_len time-series samples (10 Hz).
api::EpisodeResult SyntheticResult(const api::EpisodeSpec& spec, int series_len = 50);

}  // namespace enavi::testing
