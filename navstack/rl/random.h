#pragma once
// Portable random numbers for training and sampling: mt19937_64 raw draws turned into uniforms,
// normals and indices by our own code, so the same seed gives the same numbers with any standard
// library (std:: distributions are implementation-defined).

#include <cstdint>
#include <random>
#include <string>

namespace enavi::navstack::rl {

/// SplitMix64 finaliser: mixes a base seed with stream ids into an independent seed (e.g. one per
/// episode from (training seed, iteration, episode index)).
std::uint64_t DeriveSeed(std::uint64_t base, std::uint64_t a, std::uint64_t b = 0);

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 0) : engine_(seed) {}

  std::uint64_t NextU64() { return engine_(); }
  /// Uniform in [0, 1): the top 53 bits of one draw.
  double Uniform01() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Standard normal (Box-Muller from two uniforms; one draw pair per call, no cached spare, so
  /// the stream position depends only on the number of calls).
  double Normal();
  /// Uniform integer in [0, n), unbiased (rejection). @pre n > 0.
  std::uint64_t UniformIndex(std::uint64_t n);

  /// Engine state as text (the standard's defined mt19937_64 stream format) and back.
  std::string SaveState() const;
  /// @throws std::invalid_argument when `state` is not a valid mt19937_64 state.
  void LoadState(const std::string& state);

  bool operator==(const Rng& o) const { return engine_ == o.engine_; }

 private:
  std::mt19937_64 engine_;
};

}  // namespace enavi::navstack::rl
