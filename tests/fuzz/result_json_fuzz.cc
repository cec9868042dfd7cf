// A worker's spooled result (api::ResultMessageFromJson, read back after a restart) and the
// result JSON inside every DDS result sample (EpisodeResult's from_json): any JSON is decoded or
// refused with an exception, and a decoded result survives its own round trip.

#include <cstddef>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "api/farm_messages.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace enavi;
  const nlohmann::json j =
      nlohmann::json::parse(data, data + size, /*cb=*/nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  // The spool: what was written must read back (else a restarted worker loses the result).
  api::ResultMessage m;
  bool decoded = true;
  try {
    m = api::ResultMessageFromJson(j);
  } catch (const std::exception&) {
    decoded = false;  // refused: the spool reader names the file and moves it aside
  }
  if (decoded) {
    try {
      const api::ResultMessage again = api::ResultMessageFromJson(api::ToJson(m));
      fuzz::Check(again.episode_id == m.episode_id && again.rollout == m.rollout,
                  "spooled result changes on its round trip");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "a spooled result does not read back: %s\n", e.what());
      std::abort();
    }
  }
  // The result record of a sample.
  api::EpisodeResult r;
  try {
    r = j.get<api::EpisodeResult>();
  } catch (const std::exception&) {
    return 0;
  }
  try {
    nlohmann::json(r).get<api::EpisodeResult>();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "a result record does not survive to_json/from_json: %s\n", e.what());
    std::abort();
  }
  return 0;
}
