// A stand-in for `enavi episode --spec-file SPEC --result-file RESULT` in farm tests: it writes a
// synthetic but schema-valid api::EpisodeResult derived only from the spec (so results are
// deterministic; tests/support/synthetic_result.h), and misbehaves on demand to exercise the
// farm's fault handling.
//
// Behaviour, from the spec's overrides (per episode) or the environment (every episode):
//   fake.sleep_s        / FAKE_EPISODE_SLEEP_S         sleep before answering
//   fake.busy_s         / FAKE_EPISODE_BUSY_S          spin one core this long (CPU-bound)
//   fake.crash_attempts / FAKE_EPISODE_CRASH_ATTEMPTS  abort() while ENAVI_ATTEMPT <= N
//   fake.exit_code      / FAKE_EPISODE_EXIT_CODE       exit with this code, no result
//   fake.hang           / FAKE_EPISODE_HANG            never finish
//   fake.garbage        / FAKE_EPISODE_GARBAGE         write a result file that is not JSON
//   fake.series_len     / FAKE_EPISODE_SERIES_LEN      time series samples (default 50)
//   fake.random_sleep_s / FAKE_EPISODE_RANDOM_SLEEP_S  sleep a further random [0, this) seconds
//   fake.crash_percent  / FAKE_EPISODE_CRASH_PERCENT   abort() on this share of attempts
// The random draws hash (episode id, attempt), so a re-run of an attempt behaves the same.
// It appends "<episode id> <attempt>\n" to $FAKE_EPISODE_LOG (if set) when it starts.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "tests/support/synthetic_result.h"

namespace {

double Setting(const enavi::api::EpisodeSpec& spec, const char* key, const char* env,
               double fallback) {
  if (auto it = spec.overrides.find(key); it != spec.overrides.end()) return it->second;
  if (const char* v = std::getenv(env); v != nullptr && *v != '\0') return std::atof(v);
  return fallback;
}

// Uniform in [0, 1) from FNV-1a of `text`: stable across runs, machines and libraries.
double Draw(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

}  // namespace

int main(int argc, char** argv) {
  std::string spec_file, result_file;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--spec-file") == 0) spec_file = argv[i + 1];
    if (std::strcmp(argv[i], "--result-file") == 0) result_file = argv[i + 1];
  }
  if (spec_file.empty() || result_file.empty()) {
    std::cerr << "usage: fake_episode --spec-file SPEC.json --result-file RESULT.json\n";
    return 2;
  }
  enavi::api::EpisodeSpec spec;
  try {
    std::ifstream in(spec_file);
    spec = nlohmann::json::parse(in).get<enavi::api::EpisodeSpec>();
  } catch (const std::exception& e) {
    std::cerr << "fake_episode: bad spec " << spec_file << ": " << e.what() << "\n";
    return 2;
  }
  const char* episode = std::getenv("ENAVI_EPISODE_ID");
  const int attempt = std::getenv("ENAVI_ATTEMPT") ? std::atoi(std::getenv("ENAVI_ATTEMPT")) : 1;
  if (const char* log = std::getenv("FAKE_EPISODE_LOG"); log != nullptr && *log != '\0') {
    std::ofstream(log, std::ios::app) << (episode ? episode : "?") << " " << attempt << "\n";
  }

  const std::string draw_key = std::string(episode ? episode : "?") + "/" + std::to_string(attempt);
  const double sleep_s = Setting(spec, "fake.sleep_s", "FAKE_EPISODE_SLEEP_S", 0.0) +
                         Setting(spec, "fake.random_sleep_s", "FAKE_EPISODE_RANDOM_SLEEP_S", 0.0) *
                             Draw(draw_key + "/sleep");
  if (Setting(spec, "fake.hang", "FAKE_EPISODE_HANG", 0.0) > 0) {
    while (true) std::this_thread::sleep_for(std::chrono::hours(1));
  }
  if (sleep_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(sleep_s));
  const double busy_s = Setting(spec, "fake.busy_s", "FAKE_EPISODE_BUSY_S", 0.0);
  if (busy_s > 0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(busy_s);
    volatile double sink = 0;
    while (std::chrono::steady_clock::now() < until) {
      for (int i = 0; i < 10000; ++i) sink = sink + std::sqrt(static_cast<double>(i));
    }
  }
  const bool random_crash = 100 * Draw(draw_key + "/crash") <
                            Setting(spec, "fake.crash_percent", "FAKE_EPISODE_CRASH_PERCENT", 0.0);
  if (random_crash || attempt <= Setting(spec, "fake.crash_attempts", "FAKE_EPISODE_CRASH_ATTEMPTS", 0.0)) {
    std::cerr << "fake_episode: crashing on attempt " << attempt << " as asked\n";
    std::abort();
  }
  if (const int code = static_cast<int>(Setting(spec, "fake.exit_code", "FAKE_EPISODE_EXIT_CODE", 0))) {
    std::cerr << "fake_episode: exiting with " << code << " as asked\n";
    return code;
  }
  if (Setting(spec, "fake.garbage", "FAKE_EPISODE_GARBAGE", 0.0) > 0) {
    std::ofstream(result_file) << "this is not a result {";
    return 0;
  }

  // Synthetic flight: numbers depend only on the spec.
  const int n = static_cast<int>(Setting(spec, "fake.series_len", "FAKE_EPISODE_SERIES_LEN", 50));
  const enavi::api::EpisodeResult r = enavi::testing::SyntheticResult(spec, n);
  std::ofstream out(result_file);
  out << nlohmann::json(r).dump() << "\n";
  return out ? 0 : 1;
}
