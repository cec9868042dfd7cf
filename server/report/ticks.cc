#include "server/report/ticks.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>

namespace enavi::report {

double NiceStep(double lo, double hi, int max_ticks) {
  const double span = hi - lo;
  if (!(span > 0.0) || !std::isfinite(span)) return 1.0;
  max_ticks = std::max(1, max_ticks);
  const double raw = span / max_ticks;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * magnitude >= raw * (1.0 - 1e-9)) return m * magnitude;
  }
  return 10.0 * magnitude;
}

std::vector<double> NiceTicks(double lo, double hi, int max_ticks) {
  std::vector<double> ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return ticks;
  const double step = NiceStep(lo, hi, max_ticks);
  const double first = std::ceil(lo / step - 1e-9);
  for (double k = first; k * step <= hi + 1e-9 * step && ticks.size() < 100; k += 1.0) {
    double v = k * step;
    if (std::abs(v) < 1e-12 * step) v = 0.0;
    ticks.push_back(v);
  }
  return ticks;
}

std::string FormatTick(double value, double step) {
  int decimals = 0;
  if (step > 0.0 && std::isfinite(step)) {
    decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 6);
  }
  std::array<char, 64> buf{};
  const auto [ptr, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), value, std::chars_format::fixed, decimals);
  std::string s = ec == std::errc() ? std::string(buf.data(), ptr) : "?";
  if (s.find_first_not_of("-0.") == std::string::npos) s = decimals > 0 ? "0." + std::string(decimals, '0') : "0";
  return s;
}

}  // namespace enavi::report
