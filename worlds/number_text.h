#pragma once
// Locale-free number text for world files and OBJ: std::from_chars / std::to_chars only, so a
// file reads and writes the same on every machine whatever its locale.

#include <cstdint>
#include <string>
#include <string_view>

namespace enavi::worlds {

/// Parses a whole token as a finite double ("1.5", "-2e3", "+0.25"). False on anything else
/// (empty, trailing characters, inf, nan, out of range).
bool ParseFiniteDouble(std::string_view text, double* out);

/// Parses a whole token as a decimal integer (optional sign). False on anything else.
bool ParseInt64(std::string_view text, std::int64_t* out);
bool ParseUint64(std::string_view text, std::uint64_t* out);

/// `x` in fixed notation rounded to `decimals` digits; with `trim`, trailing zeros are cut to
/// one decimal ("1.5", "2.0", "-0.0001"), without it all digits stay ("0.30"). A zero never
/// carries a minus sign.
std::string FormatFixed(double x, int decimals = 4, bool trim = true);

}  // namespace enavi::worlds
