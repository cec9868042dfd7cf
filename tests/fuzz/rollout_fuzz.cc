// Rollouts: the binary blob a worker sends (navstack::rl::DecodeRollout), its JSON form, the
// learned method's compressed blob (DecodeNavRollout) and the HTTP rollout stream
// (api::DecodeRolloutStream). The first byte picks the decoder; any input is
// decoded or refused naming the source, and a decoded blob re-encodes to one that decodes.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "api/rollout_records.h"
#include "navstack/rl/nav_rollout.h"
#include "navstack/rl/rollout.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace enavi;
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  constexpr const char* kSource = "fuzz-rollout";
  try {
    switch (data[0] % 4) {
      case 0: {
        const navstack::rl::Rollout r = navstack::rl::DecodeRollout(bytes, kSource);
        navstack::rl::DecodeRollout(navstack::rl::EncodeRollout(r), "re-encoded");
        break;
      }
      case 1: {
        const navstack::rl::Rollout r = navstack::rl::DeserializeRollout(std::string(bytes), kSource);
        navstack::rl::DeserializeRollout(navstack::rl::SerializeRollout(r), "re-serialised");
        break;
      }
      case 3: {
        const navstack::rl::NavRollout r = navstack::rl::DecodeNavRollout(bytes, kSource);
        navstack::rl::DecodeNavRollout(navstack::rl::EncodeNavRollout(r), "re-encoded");
        break;
      }
      default: {
        const auto records = api::DecodeRolloutStream(bytes, kSource);
        api::DecodeRolloutStream(api::EncodeRolloutStream(records), "re-encoded");
      }
    }
  } catch (const std::exception& e) {
    // A re-encoded record that fails to decode names "re-...", not the source: a crash.
    fuzz::CheckNamesSource(e, kSource);
  }
  return 0;
}
