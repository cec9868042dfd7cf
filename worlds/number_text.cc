#include "worlds/number_text.h"

#include <array>
#include <charconv>
#include <cmath>
#include <system_error>

namespace enavi::worlds {

std::string FormatFixed(double x, int decimals, bool trim) {
  std::array<char, 512> buf{};
  const auto [ptr, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), x, std::chars_format::fixed, decimals);
  std::string s = ec == std::errc() ? std::string(buf.data(), ptr) : std::string("nan");
  // Trim trailing zeros, keeping one digit after the point.
  if (const auto dot = s.find('.'); trim && dot != std::string::npos) {
    std::size_t end = s.size();
    while (end > dot + 2 && s[end - 1] == '0') --end;
    s.resize(end);
  }
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

}  // namespace enavi::worlds
