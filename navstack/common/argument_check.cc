#include "navstack/common/argument_check.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace enavi::navstack {

void ArgumentCheck::Range(bool ok, const char* field, double value, const char* range) const {
  if (!ok) {
    throw std::invalid_argument(std::string(owner_) + "." + field + ": " + std::to_string(value) +
                                " is out of range " + range);
  }
}

void ArgumentCheck::NonNegative(double value, const char* name) const {
  if (!(value >= 0.0) || std::isinf(value)) {
    throw std::domain_error(std::string(owner_) + ": " + name + " = " + std::to_string(value) +
                            " must be finite and >= 0");
  }
}

}  // namespace enavi::navstack
