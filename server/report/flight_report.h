#pragma once
// What `enavi fly --out DIR` writes next to result.json: the time series as CSV and the flight
// as pictures (bird's-eye path coloured by eci, speed over time, and for E-Navi the adaptation).

#include <string>

#include "api/episode.h"
#include "worlds/world.h"

namespace enavi::report {

/// t, position, velocity, speed, eci, f_per, f_col, f_dif, res, utilisation, events.
std::string TimeSeriesCsv(const api::TimeSeries& series);

/// Writes DIR/flight_topdown.png, DIR/speed.png and DIR/adaptation.png. Throws
/// std::runtime_error naming the file if one cannot be written.
void WriteFlightPlots(const api::EpisodeResult& result, const worlds::World& world, const std::string& dir);

}  // namespace enavi::report
