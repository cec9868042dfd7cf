#include "api/rollout_records.h"

#include <cstring>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace enavi::api {
namespace {

constexpr char kMagic[4] = {'E', 'N', 'R', 'S'};

void PutU32(std::string* out, std::uint32_t v) { out->append(reinterpret_cast<const char*>(&v), 4); }

}  // namespace

std::string EncodeRolloutStream(const std::vector<StoredRollout>& records) {
  std::string out(kMagic, 4);
  PutU32(&out, static_cast<std::uint32_t>(records.size()));
  for (const StoredRollout& r : records) {
    const std::string meta = nlohmann::json{
        {"episode_id", r.episode_id}, {"index", r.index}, {"attempt", r.attempt},
        {"worker", r.worker}, {"board", r.board}, {"scenario", r.scenario}, {"world", r.world},
        {"seed", r.seed}, {"policy_hash", r.policy_hash}, {"success", r.success},
        {"collided", r.collided}, {"flight_time_s", r.flight_time_s},
        {"nav_cpu_util_pct", r.nav_cpu_util_pct}}.dump();
    PutU32(&out, static_cast<std::uint32_t>(meta.size()));
    out += meta;
    PutU32(&out, static_cast<std::uint32_t>(r.rollout.size()));
    out += r.rollout;
  }
  return out;
}

std::vector<StoredRollout> DecodeRolloutStream(std::string_view bytes, const std::string& source) {
  std::size_t at = 0;
  auto fail = [&](const std::string& why) -> void {
    throw std::invalid_argument(source + ": rollout stream: " + why);
  };
  auto u32 = [&]() {
    std::uint32_t v = 0;
    if (bytes.size() - at < 4) fail("truncated");
    std::memcpy(&v, bytes.data() + at, 4);
    at += 4;
    return v;
  };
  auto take = [&](std::size_t n) {
    if (bytes.size() - at < n) fail("truncated");
    const std::string_view v = bytes.substr(at, n);
    at += n;
    return v;
  };
  if (bytes.size() < 4 || bytes.substr(0, 4) != std::string_view(kMagic, 4)) fail("not an ENRS stream");
  at = 4;
  const std::uint32_t count = u32();
  std::vector<StoredRollout> out;
  for (std::uint32_t i = 0; i < count; ++i) {
    StoredRollout r;
    try {
      const nlohmann::json j = nlohmann::json::parse(take(u32()));
      r.episode_id = j.at("episode_id");
      r.index = j.at("index");
      r.attempt = j.at("attempt");
      r.worker = j.at("worker");
      r.board = j.at("board");
      r.scenario = j.at("scenario");
      r.world = j.at("world");
      r.seed = j.at("seed");
      r.policy_hash = j.at("policy_hash");
      r.success = j.at("success");
      r.collided = j.at("collided");
      r.flight_time_s = j.at("flight_time_s");
      r.nav_cpu_util_pct = j.at("nav_cpu_util_pct");
    } catch (const nlohmann::json::exception& e) {
      fail("record " + std::to_string(i) + ": " + e.what());
    }
    r.rollout = std::string(take(u32()));
    out.push_back(std::move(r));
  }
  if (at != bytes.size()) fail("trailing bytes");
  return out;
}

}  // namespace enavi::api
