#pragma once
// Locale-free number text: std::from_chars only, so a file reads the same on every machine
// whatever its locale. The one number parser of the YAML reader, world files, meshes and CLI values.

#include <cstdint>
#include <string_view>

namespace enavi::api {

/// Parses a whole token as a finite double ("1.5", "-2e3", "+0.25"). False on anything else
/// (empty, trailing characters, inf, nan, out of range).
bool ParseFiniteDouble(std::string_view text, double* out);

/// Parses a whole token as a decimal integer (optional sign). False on anything else.
bool ParseInt64(std::string_view text, std::int64_t* out);
bool ParseUint64(std::string_view text, std::uint64_t* out);

}  // namespace enavi::api
