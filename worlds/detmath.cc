#include "worlds/detmath.h"

namespace enavi::worlds::detmath {

void SinCos(double x, double* s, double* c) {
  // Cody-Waite reduction by pi/2: the first constant has trailing zero bits so k * kPio2Hi is exact.
  constexpr double kTwoOverPi = 0.63661977236758134308;
  constexpr double kPio2Hi = 1.57079632673412561417e+00;
  constexpr double kPio2Lo = 6.07710050650619224932e-11;
  const double k = std::round(x * kTwoOverPi);
  const double r = (x - k * kPio2Hi) - k * kPio2Lo;
  // Taylor series on |r| <= pi/4 (+ a little): the r^19 / r^18 terms are below 1e-17.
  const double r2 = r * r;
  double sp = 1.0 / 355687428096000.0;  // 1/17!
  sp = sp * r2 - 1.0 / 1307674368000.0;  // 1/15!
  sp = sp * r2 + 1.0 / 6227020800.0;     // 1/13!
  sp = sp * r2 - 1.0 / 39916800.0;       // 1/11!
  sp = sp * r2 + 1.0 / 362880.0;         // 1/9!
  sp = sp * r2 - 1.0 / 5040.0;
  sp = sp * r2 + 1.0 / 120.0;
  sp = sp * r2 - 1.0 / 6.0;
  const double sin_r = r + r * r2 * sp;
  double cp = 1.0 / 6402373705728000.0;  // 1/18!
  cp = cp * r2 - 1.0 / 20922789888000.0;  // 1/16!
  cp = cp * r2 + 1.0 / 87178291200.0;     // 1/14!
  cp = cp * r2 - 1.0 / 479001600.0;       // 1/12!
  cp = cp * r2 + 1.0 / 3628800.0;         // 1/10!
  cp = cp * r2 - 1.0 / 40320.0;
  cp = cp * r2 + 1.0 / 720.0;
  cp = cp * r2 - 1.0 / 24.0;
  cp = cp * r2 + 0.5;
  const double cos_r = 1.0 - r2 * cp;
  // Quadrant of x: rotate (cos r, sin r) by k * 90 degrees.
  const std::int64_t q = static_cast<std::int64_t>(k) & 3;
  switch (q) {
    case 0: *s = sin_r; *c = cos_r; break;
    case 1: *s = cos_r; *c = -sin_r; break;
    case 2: *s = -sin_r; *c = -cos_r; break;
    default: *s = -cos_r; *c = sin_r; break;
  }
}

}  // namespace enavi::worlds::detmath
