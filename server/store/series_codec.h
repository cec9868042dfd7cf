#pragma once
// The compact binary form of a result's time series in the results table ("ENS1"): what the
// episode page and the bird's-eye view read back. A new series column is added here and in
// api::TimeSeries, nowhere else in the store.

#include <cstdint>
#include <vector>

#include "api/episode.h"

namespace enavi::server {

/// Packs a time series into the compact binary form stored in the results table.
std::vector<std::uint8_t> PackSeries(const api::TimeSeries& series);
/// @throws std::invalid_argument on a malformed blob.
api::TimeSeries UnpackSeries(const std::vector<std::uint8_t>& blob);

}  // namespace enavi::server
