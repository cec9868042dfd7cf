#include "server/report/colormap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace enavi::report {

Rgb Viridis(double t) {
  // Control points at t = 0, 1/8, ..., 1 (RGB 0..255).
  static constexpr std::array<std::array<double, 3>, 9> kPoints = {{{68, 1, 84},
                                                                    {72, 40, 120},
                                                                    {62, 73, 137},
                                                                    {49, 104, 142},
                                                                    {38, 130, 142},
                                                                    {31, 158, 137},
                                                                    {53, 183, 121},
                                                                    {110, 206, 88},
                                                                    {253, 231, 37}}};
  if (std::isnan(t)) return colors::kGrey;
  t = std::clamp(t, 0.0, 1.0);
  const double f = t * (kPoints.size() - 1);
  const auto i = std::min<std::size_t>(static_cast<std::size_t>(f), kPoints.size() - 2);
  const double u = f - static_cast<double>(i);
  auto mix = [&](int c) { return ((1.0 - u) * kPoints[i][c] + u * kPoints[i + 1][c]) / 255.0; };
  return {mix(0), mix(1), mix(2)};
}

Rgb GreyRamp(double t) {
  if (std::isnan(t)) t = 0.5;
  t = std::clamp(t, 0.0, 1.0);
  const double v = 0.82 - 0.6 * t;
  return {v, v, v};
}

double Normalize(double value, double lo, double hi) {
  if (!(hi > lo)) return 0.5;
  return std::clamp((value - lo) / (hi - lo), 0.0, 1.0);
}

}  // namespace enavi::report
