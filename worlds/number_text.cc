#include "worlds/number_text.h"

#include <array>
#include <charconv>
#include <cmath>
#include <system_error>

namespace enavi::worlds {
namespace {

// from_chars rejects a leading '+', which YAML and OBJ writers sometimes emit.
std::string_view StripPlus(std::string_view s) {
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}

}  // namespace

bool ParseFiniteDouble(std::string_view text, double* out) {
  text = StripPlus(text);
  if (text.empty()) return false;
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v, std::chars_format::general);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool ParseInt64(std::string_view text, std::int64_t* out) {
  text = StripPlus(text);
  if (text.empty()) return false;
  std::int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size()) return false;
  *out = v;
  return true;
}

bool ParseUint64(std::string_view text, std::uint64_t* out) {
  text = StripPlus(text);
  if (text.empty() || text[0] == '-') return false;
  std::uint64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size()) return false;
  *out = v;
  return true;
}

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
