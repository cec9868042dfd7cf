#include "api/number_parse.h"

#include <charconv>
#include <cmath>
#include <system_error>

namespace enavi::api {
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

}  // namespace enavi::api
