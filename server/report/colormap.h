#pragma once
// Colour maps for values along paths and heights of obstacles.

#include "server/report/canvas.h"

namespace enavi::report {

/// Viridis-like perceptually ordered map (dark purple -> blue -> green -> yellow), t in [0, 1]
/// (clamped; NaN maps to grey). Piecewise linear through nine control points.
Rgb Viridis(double t);

/// Grey ramp for obstacle heights: t = 0 light grey (low), t = 1 dark grey (tall).
Rgb GreyRamp(double t);

/// Maps `value` in [lo, hi] to [0, 1] (clamped; lo == hi gives 0.5).
double Normalize(double value, double lo, double hi);

}  // namespace enavi::report
