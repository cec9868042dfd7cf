// Policy files (navstack/rl/policy_io.h): any bytes either load as a frequency policy that
// writes back and loads again, or are refused with an error naming the source.

#include <cstddef>
#include <cstdint>
#include <string>

#include "navstack/rl/policy_io.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace enavi;
  constexpr const char* kSource = "fuzz-policy.json";
  const std::string text(reinterpret_cast<const char*>(data), size);
  navstack::rl::PolicyFile policy;
  try {
    policy = navstack::rl::FrequencyPolicyFromText(text, kSource);
  } catch (const std::exception& e) {
    fuzz::CheckNamesSource(e, kSource);
    return 0;
  }
  try {
    navstack::rl::FrequencyPolicyFromText(navstack::rl::CanonicalPolicyText(policy), "rewritten");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "an accepted policy does not load again: %s\n", e.what());
    std::abort();
  }
  return 0;
}
