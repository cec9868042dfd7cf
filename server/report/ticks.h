#pragma once
// Axis ticks at "nice" numbers (1, 2, 5 x 10^k) and their labels.

#include <string>
#include <vector>

namespace enavi::report {

/// Step between ticks: the smallest of 1, 2, 5 x 10^k that gives at most `max_ticks` intervals.
double NiceStep(double lo, double hi, int max_ticks = 6);

/// Tick values that are multiples of NiceStep inside [lo, hi].
std::vector<double> NiceTicks(double lo, double hi, int max_ticks = 6);

/// A tick label with as many decimals as `step` needs ("0.25", "10", "-3.5"); locale-free.
std::string FormatTick(double value, double step);

}  // namespace enavi::report
