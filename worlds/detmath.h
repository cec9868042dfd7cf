#pragma once
// Machine-independent arithmetic for everything that decides what a generated world contains.
// libm's sin/cos may differ in the last bit between C libraries and CPUs; these use only
// + - * / and exactly rounded operations (round, sqrt), so their results are the same on every
// IEEE-754 machine (the worlds library is compiled with -ffp-contract=off: no fused multiply-add).

#include <cmath>
#include <cstdint>

namespace enavi::worlds::detmath {

inline constexpr double kPi = 3.14159265358979323846;

/// sin and cos of `x` (radians), accurate to about 1 ulp for |x| < 1e5. Defined out of line in
/// detmath.cc so every caller uses the copy compiled without contraction.
void SinCos(double x, double* s, double* c);

inline double Sin(double x) { double s, c; SinCos(x, &s, &c); return s; }
inline double Cos(double x) { double s, c; SinCos(x, &s, &c); return c; }

/// `x` rounded to a multiple of 10^-4 (the world file precision), with -0 turned into +0.
inline double Quantize(double x) { return std::round(x * 1e4) / 1e4 + 0.0; }

}  // namespace enavi::worlds::detmath
