// Closed-loop episodes through the built `enavi fly`: byte-identical outputs, the files `--out`
// writes, the `--json` record, and the worker contract (`enavi episode --spec-file S --result-file R`).
#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "server/report/canvas.h"
#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"

namespace enavi::integration {
namespace {

std::vector<std::string> Split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(text);
  while (std::getline(in, field, sep)) out.push_back(field);
  if (!text.empty() && text.back() == sep) out.emplace_back();
  return out;
}

TEST(FlyCliTest, OutTwiceGivesByteIdenticalFiles) {
  TempDir dir;
  const std::string a = (dir.path() / "a").string(), b = (dir.path() / "b").string();
  // A forest flight cut at 3 s: replans among trees, sensor noise, the whole pipeline.
  const std::string args = "fly --world forest --param length=10 --seed 3 --board host --method baseline "
                           "--clock virtual --cost model --timeout 3 --out ";
  CliRun r = Enavi(dir, args + a);
  ASSERT_EQ(r.code, 0) << r.err;
  r = Enavi(dir, args + b);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* file :
       {"result.json", "timeseries.csv", "eci_frames.csv", "flight_topdown.png", "speed.png", "adaptation.png",
        "eci_frames.png"}) {
    const std::string first = ReadFile(dir.path() / "a" / file);
    ASSERT_FALSE(first.empty()) << file;
    EXPECT_TRUE(first == ReadFile(dir.path() / "b" / file)) << file << " differs between two identical runs";
  }
}

TEST(FlyCliTest, OutWritesTheResultTheTimeSeriesAndFourPlotsThatDecode) {
  TempDir dir;
  const auto out = dir.path() / "out";
  const CliRun r = Enavi(dir, "fly --world empty --param length=6 --seed 1 --json --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;

  // --json: one object with the keys, nested as written there.
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  for (const char* key : {"scenario", "seed", "board", "method", "clock", "cost", "success", "collided", "timed_out",
                          "flight_time_s", "path_length_m", "velocity_mean_mps", "velocity_std_mps",
                          "accel_peak_mps2", "nav_cpu_util_pct", "deadline_miss_ratio", "replans",
                          "eci_time_ms_mean", "adapter_time_ms_mean"})
    EXPECT_TRUE(summary.contains(key)) << key;
  for (const char* key : {"perception", "planning", "collision", "difference"})
    EXPECT_TRUE(summary["task_cpu_util_pct"].contains(key)) << "task_cpu_util_pct." << key;
  for (const char* key : {"min", "mean", "max"}) EXPECT_TRUE(summary["eci"].contains(key)) << "eci." << key;
  EXPECT_EQ(summary["success"], true) << r.out;
  EXPECT_EQ(summary["scenario"], "empty");
  double sum = 0;
  for (const auto& [task, pct] : summary["task_cpu_util_pct"].items()) sum += pct.get<double>();
  EXPECT_NEAR(summary["nav_cpu_util_pct"].get<double>(), sum, 1e-9) << "nav CPU is the sum of the four tasks";
  EXPECT_EQ(summary["adapter_time_ms_mean"], 0.0) << "the baseline has no adapter";

  // result.json: the full record without the series (that is timeseries.csv), same numbers.
  const nlohmann::json full = nlohmann::json::parse(ReadFile(out / "result.json"));
  EXPECT_FALSE(full.contains("series"));
  ASSERT_TRUE(full.contains("events"));
  ASSERT_TRUE(full.contains("spec"));
  const auto result = full.get<api::EpisodeResult>();
  EXPECT_EQ(api::ResultSummaryJson(result), summary) << "--json and result.json disagree";

  // timeseries.csv: the documented columns, a row every 0.1 s from the start to the end.
  const std::vector<std::string> lines = Split(ReadFile(out / "timeseries.csv"), '\n');
  ASSERT_GE(lines.size(), 3u);
  EXPECT_EQ(lines[0], "t,x,y,z,vx,vy,vz,speed,eci,f_per,f_col,f_dif,res,utilisation,events");
  EXPECT_TRUE(lines.back().empty()) << "file ends with a newline";
  const std::size_t rows = lines.size() - 2;
  EXPECT_NEAR(static_cast<double>(rows), result.flight_time_s / 0.1 + 1, 1.0) << "10 Hz rows";
  bool saw_replan = false;
  for (std::size_t i = 0; i < rows; ++i) {
    const std::vector<std::string> f = Split(lines[i + 1], ',');
    ASSERT_EQ(f.size(), 15u) << "row " << i << ": " << lines[i + 1];
    const double t = std::stod(f[0]);
    EXPECT_NEAR(t, 0.1 * static_cast<double>(i), 1e-6) << lines[i + 1];
    const double vx = std::stod(f[4]), vy = std::stod(f[5]), vz = std::stod(f[6]);
    EXPECT_NEAR(std::stod(f[7]), std::sqrt(vx * vx + vy * vy + vz * vz), 2e-4) << "speed = |v|: " << lines[i + 1];
    const double eci = std::stod(f[8]);
    EXPECT_TRUE(eci >= 0 && eci <= 1) << lines[i + 1];
    EXPECT_EQ(f[9], "30.00") << "baseline f_per";
    EXPECT_EQ(f[12], "0.100") << "baseline resolution";
    saw_replan |= f[14].find("replan") != std::string::npos;
  }
  EXPECT_TRUE(saw_replan) << "the events column records replans";
  const std::vector<std::string> first = Split(lines[1], ',');
  EXPECT_EQ(first[1] + "," + first[2] + "," + first[3], "-3.0000,0.0000,1.5000") << "starts at the world's start";

  // eci_frames.csv: every depth frame (30 Hz) with what its eci came from; the frames marked in
  // flight are the ones the result's flight range summarises.
  const std::vector<std::string> frames = Split(ReadFile(out / "eci_frames.csv"), '\n');
  ASSERT_GE(frames.size(), 3u);
  EXPECT_EQ(frames[0],
            "t,eci,d0,d_ahead,layers,occupied_zones,valid_pixels,velocity_aligned,speed,camera_pitch_deg,in_flight");
  EXPECT_TRUE(frames.back().empty()) << "file ends with a newline";
  const std::size_t frame_rows = frames.size() - 2;
  EXPECT_NEAR(static_cast<double>(frame_rows), result.flight_time_s * 30.0, 2.0) << "a row per 30 Hz frame";
  std::int64_t in_flight = 0;
  double lo = 1.0, hi = 0.0;
  for (std::size_t i = 0; i < frame_rows; ++i) {
    const std::vector<std::string> f = Split(frames[i + 1], ',');
    ASSERT_EQ(f.size(), 11u) << "row " << i << ": " << frames[i + 1];
    const double eci = std::stod(f[1]);
    EXPECT_TRUE(eci >= 0 && eci <= 1) << frames[i + 1];
    EXPECT_GE(std::stoi(f[4]), 1) << "at least one layer: " << frames[i + 1];
    if (f[10] == "1") {
      ++in_flight;
      lo = std::min(lo, eci);
      hi = std::max(hi, eci);
    }
  }
  EXPECT_EQ(in_flight, result.eci.flight_frames);
  EXPECT_NEAR(lo, result.eci.flight_min, 1e-4);
  EXPECT_NEAR(hi, result.eci.flight_max, 1e-4);

  // Plots: PNGs that decode, of a readable size, with something drawn on them.
  for (const char* png : {"flight_topdown.png", "speed.png", "adaptation.png", "eci_frames.png"}) {
    const report::PngImage img = report::ReadPng((out / png).string());
    EXPECT_GE(img.width, 400) << png;
    EXPECT_GE(img.height, 300) << png;
    EXPECT_LE(img.width, 4000) << png;
    EXPECT_LE(img.height, 4000) << png;
    const std::set<std::uint32_t> colours(img.argb.begin(), img.argb.end());
    EXPECT_GT(colours.size(), 10u) << png << " looks blank";
  }
}

TEST(FlyCliTest, SpecFileAndResultFileRoundTripLikeTheWorkerRunsThem) {
  TempDir dir;
  api::EpisodeSpec spec = Spec("forest", 2, {{"length", "10"}});
  spec.board = "tx2";
  spec.timeout_s = 2.5;
  spec.overrides = {{"camera.noise_k", 0.01}};
  const auto spec_file = dir.Write("spec.json", nlohmann::json(spec).dump(2));
  const auto result_file = dir.path() / "result.json";

  const CliRun r = Enavi(dir, "episode --spec-file " + spec_file.string() + " --result-file " + result_file.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "") << "the worker reads the result file; stdout stays quiet";

  // The file holds the full record (series included), and parsing it loses nothing.
  const nlohmann::json written = nlohmann::json::parse(ReadFile(result_file));
  const auto result = written.get<api::EpisodeResult>();
  EXPECT_EQ(nlohmann::json(result), written) << "EpisodeResult JSON round trip is lossy";
  EXPECT_EQ(nlohmann::json(result.spec), nlohmann::json(spec)) << "the result carries the spec it flew";
  EXPECT_TRUE(result.timed_out) << Describe(result);
  EXPECT_GT(result.series.size(), 20u);

  // The child process flew exactly what the same spec flies in process.
  EXPECT_EQ(nlohmann::json(sim::RunEpisode(spec)), written);
}

}  // namespace
}  // namespace enavi::integration
