#include "navstack/rl/random.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack::rl {
namespace {

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

std::uint64_t DeriveSeed(std::uint64_t base, std::uint64_t a, std::uint64_t b) {
  return SplitMix64(SplitMix64(SplitMix64(base) ^ a) ^ b);
}

double Rng::Normal() {
  // u1 in (0, 1] so the log is finite.
  const double u1 = 1.0 - Uniform01();
  const double u2 = Uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

std::uint64_t Rng::UniformIndex(std::uint64_t n) {
  if (n == 0) throw std::logic_error("Rng::UniformIndex: n must be > 0");
  // Reject the top partial bucket so every index is equally likely.
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() -
                              std::numeric_limits<std::uint64_t>::max() % n;
  std::uint64_t x;
  do {
    x = engine_();
  } while (x >= limit);
  return x % n;
}

std::string Rng::SaveState() const {
  std::ostringstream os;
  os << engine_;
  return os.str();
}

void Rng::LoadState(const std::string& state) {
  std::istringstream is(state);
  std::mt19937_64 e;
  is >> e;
  if (is.fail()) throw std::invalid_argument("rng state: not a valid mt19937_64 state");
  is >> std::ws;
  if (!is.eof()) throw std::invalid_argument("rng state: trailing characters");
  engine_ = e;
}

}  // namespace enavi::navstack::rl
