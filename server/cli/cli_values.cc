#include "server/cli/cli_values.h"

#include <stdexcept>

#include "worlds/number_text.h"

namespace enavi::cli {

api::Vec3 ParsePoint(const std::string& flag, const std::string& text) {
  api::Vec3 p{};
  std::size_t pos = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = text.find(',', pos);
    const bool last = i == 2;
    if (last != (comma == std::string::npos) ||
        !worlds::ParseFiniteDouble(text.substr(pos, last ? std::string::npos : comma - pos), &p[i])) {
      throw std::invalid_argument(flag + ": expected x,y,z in metres (got '" + text + "')");
    }
    pos = comma + 1;
  }
  return p;
}

std::map<std::string, std::string> ParseNameValues(const std::string& flag, const std::vector<std::string>& items) {
  std::map<std::string, std::string> values;
  for (const std::string& item : items) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument(flag + ": expected name=value (got '" + item + "')");
    if (!values.emplace(item.substr(0, eq), item.substr(eq + 1)).second)
      throw std::invalid_argument(flag + ": '" + item.substr(0, eq) + "' given twice");
  }
  return values;
}

double ParseNumber(const std::string& flag, const std::string& name, const std::string& text) {
  double v = 0;
  if (!worlds::ParseFiniteDouble(text, &v))
    throw std::invalid_argument(flag + " " + name + ": '" + text + "' is not a number");
  return v;
}

}  // namespace enavi::cli
