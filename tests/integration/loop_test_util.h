#pragma once
// Helpers for the closed-loop tests: episode specs, a one-line account of a result for failure
// messages, the per-task notes of a result, and running the built `enavi` binary.

#include <sys/wait.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "api/episode.h"
#include "tests/unit/worlds/test_util.h"

namespace enavi::integration {

using worlds::testing::ReadFile;
using worlds::testing::TempDir;

/// The baseline on the host board, virtual clock, cost model: the reproducible default.
inline api::EpisodeSpec Spec(const std::string& world, std::uint64_t seed,
                             std::map<std::string, std::string> params = {}) {
  api::EpisodeSpec spec;
  spec.world = world;
  spec.seed = seed;
  spec.world_params = std::move(params);
  spec.board = "host";
  spec.method = "baseline";
  spec.clock = "virtual";
  spec.cost = "model";
  return spec;
}

/// What happened, in one line, for assertion messages.
inline std::string Describe(const api::EpisodeResult& r) {
  std::ostringstream out;
  out << r.spec.method << " on " << r.spec.board << ", " << r.spec.world << " seed " << r.spec.seed << ": "
      << r.end_reason << " after " << r.flight_time_s << " s, path " << r.path_length_m << " m (straight "
      << r.straight_line_m << " m), replans " << r.replans << ", deadline misses " << r.deadline_misses << "/"
      << r.jobs_released;
  if (r.collision_point)
    out << ", collision at (" << (*r.collision_point)[0] << ", " << (*r.collision_point)[1] << ", "
        << (*r.collision_point)[2] << ")";
  for (const auto& [k, v] : r.notes)
    if (k.rfind("task.", 0) == 0 || k == "plan_failures") out << "; " << k << ": " << v;
  return out.str();
}

/// One task's line of the result notes: "released N, late N, skipped N, mean job X ms, max Y ms".
struct TaskNote {
  long released = -1, late = -1, skipped = -1;
  double mean_job_ms = -1, max_job_ms = -1;
};

inline TaskNote ReadTaskNote(const api::EpisodeResult& r, const std::string& task) {
  TaskNote n;
  const auto it = r.notes.find("task." + task);
  if (it == r.notes.end()) {
    ADD_FAILURE() << "result notes have no task." << task;
    return n;
  }
  const int got = std::sscanf(it->second.c_str(), "released %ld, late %ld, skipped %ld, mean job %lf ms, max %lf ms",
                              &n.released, &n.late, &n.skipped, &n.mean_job_ms, &n.max_job_ms);
  EXPECT_EQ(got, 5) << "task." << task << " note not in the documented form: " << it->second;
  return n;
}

struct CliRun {
  int code = -1;
  std::string out, err;
};

/// Runs `<build>/bin/enavi ARGS` with stdout and stderr captured in files under `dir`.
inline CliRun Enavi(const TempDir& dir, const std::string& args) {
  static int calls = 0;
  const std::string tag = std::to_string(calls++);
  const auto out = dir.path() / ("stdout" + tag + ".txt"), err = dir.path() / ("stderr" + tag + ".txt");
  const std::string cmd =
      std::string(ENAVI_BINARY_DIR) + "/bin/enavi " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

}  // namespace enavi::integration
