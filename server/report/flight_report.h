#pragma once
// What `enavi fly --out DIR` writes next to result.json: the time series as CSV and the flight
// as pictures (bird's-eye path coloured by eci, speed over time, and for E-Navi the adaptation),
// and the eci of every depth frame.

#include <cstdint>
#include <string>
#include <vector>

#include "api/episode.h"
#include "worlds/world.h"

namespace enavi::report {

/// t, position, velocity, speed, eci, f_per, f_col, f_dif, res, utilisation, [wind_speed],
/// [odometry_error], events (the bracketed columns when the episode has them).
std::string TimeSeriesCsv(const api::TimeSeries& series);

/// Writes DIR/flight_topdown.png, DIR/speed.png and DIR/adaptation.png. Throws
/// std::runtime_error naming the file if one cannot be written.
/// The bird's-eye view of a flight (path coloured by eci, collision marked) as PNG bytes,
/// `width` px wide: the dashboard's episode picture.
std::vector<std::uint8_t> FlightTopDownPng(const api::EpisodeResult& result, const worlds::World& world,
                                           int width = 1000);

void WriteFlightPlots(const api::EpisodeResult& result, const worlds::World& world, const std::string& dir);

/// Every depth frame's eci with what it came from, one value per frame.
struct EciFrameSeries {
  std::vector<double> t, eci, d0, camera_pitch_deg;
};
/// Writes `path` (PNG) for the flight `result`: eci per frame, its nearest return d0 and the
/// camera's pitch over time, the pictures behind a flight's eci range. Throws
/// std::runtime_error naming the file if it cannot be written.
void WriteEciFramesPlot(const api::EpisodeResult& result, const EciFrameSeries& frames, const std::string& path);

}  // namespace enavi::report
