#include "api/fixed.h"

#include <fmt/format.h>

namespace enavi::api {

std::string Fixed(double v, int digits) { return fmt::format("{:.{}f}", v, digits); }

}  // namespace enavi::api
