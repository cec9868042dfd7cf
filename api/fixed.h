#pragma once
// The one number formatter for text people read (tables, notes, messages): fixed decimals, via
// fmt. Files whose bytes must not change across machines or versions (world files, golden
// outputs) keep their own writer, worlds/number_text.h.

#include <string>

namespace enavi::api {

/// `v` with exactly `digits` decimals, rounded to nearest ("2.50" for Fixed(2.5, 2)).
std::string Fixed(double v, int digits);

}  // namespace enavi::api
