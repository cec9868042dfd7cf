#pragma once
// Locale-free number text for world files and OBJ: std::to_chars for writing (the parsers are
// api/number_parse.h), so a file reads and writes the same on every machine whatever its locale.

#include <cstdint>
#include <string>
#include <string_view>

#include "api/number_parse.h"

namespace enavi::worlds {

// The parsers are api's (one home for number text to value); the worlds readers name them here.
using api::ParseFiniteDouble;
using api::ParseInt64;
using api::ParseUint64;

/// `x` in fixed notation rounded to `decimals` digits; with `trim`, trailing zeros are cut to
/// one decimal ("1.5", "2.0", "-0.0001"), without it all digits stay ("0.30"). A zero never
/// carries a minus sign.
std::string FormatFixed(double x, int decimals = 4, bool trim = true);

}  // namespace enavi::worlds
