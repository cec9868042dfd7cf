// The host calibration file: round trip, where it lives, stale or missing detection, and board
// speeds relative to the host.
#include "workers/board/host_calibration.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace enavi::board {
namespace {

namespace fs = std::filesystem;

class HostCalibrationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("enavi-hostcal-" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static HostCalibration Sample() {
    HostCalibration c;
    c.relative_speed = 1.25;
    c.fitted["navstack"].ns_per_unit[static_cast<int>(navstack::WorkUnit::kRayStep)] = 21.5;
    c.fitted["navstack"].ns_per_job[static_cast<int>(navstack::TaskId::kCollision)] = 3500.0;
    c.fitted["ego_planner"].ns_per_unit[static_cast<int>(navstack::WorkUnit::kRayStep)] = 7.0;
    c.samples = 1234;
    c.r2 = 0.93;
    c.cpu_model = "Test CPU 9000";
    c.kernel = "6.1.0-test";
    c.date = "2025-01-02T03:04:05Z";
    c.reference_calibration_id = "ref-1";
    c.tasks["perception"] = {100, 0.010, 0.020, 0.025};
    c.tasks["planning"] = {50, 0.020, 0.040, 0.050};
    return c;
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

TEST_F(HostCalibrationTest, SaveLoadRoundTrip) {
  const std::string path = Path("sub/dir/calibration.json");
  SaveHostCalibration(Sample(), path);
  const HostCalibration c = LoadHostCalibration(path);
  EXPECT_EQ(c.relative_speed, 1.25);
  ASSERT_EQ(c.fitted.size(), 2u);
  EXPECT_EQ(c.fitted.at("navstack").ns_per_unit[static_cast<int>(navstack::WorkUnit::kRayStep)], 21.5);
  EXPECT_EQ(c.fitted.at("navstack").ns_per_job[static_cast<int>(navstack::TaskId::kCollision)], 3500.0);
  EXPECT_EQ(c.fitted.at("navstack").ns_per_job[static_cast<int>(navstack::TaskId::kPlanning)], 0.0);
  EXPECT_EQ(c.fitted.at("ego_planner").ns_per_unit[static_cast<int>(navstack::WorkUnit::kRayStep)], 7.0);
  EXPECT_EQ(c.samples, 1234);
  EXPECT_EQ(c.cpu_model, "Test CPU 9000");
  EXPECT_EQ(c.kernel, "6.1.0-test");
  EXPECT_EQ(c.date, "2025-01-02T03:04:05Z");
  EXPECT_EQ(c.reference_calibration_id, "ref-1");
  ASSERT_EQ(c.tasks.count("planning"), 1u);
  EXPECT_EQ(c.tasks.at("planning").max_s, 0.050);
  EXPECT_EQ(c.tasks.at("perception").jobs, 100);
  EXPECT_EQ(c.probe_speed, 0.0) << "a calibration without a speed probe (written before it existed) still reads";

  HostCalibration probed = Sample();
  probed.probe_speed = 1.31;
  SaveHostCalibration(probed, path);
  EXPECT_EQ(LoadHostCalibration(path).probe_speed, 1.31);
}

TEST_F(HostCalibrationTest, ABadProbeSpeedIsRefusedWithTheFieldNamed) {
  HostCalibration c = Sample();
  c.probe_speed = 1.31;
  const std::string path = Path("c.json");
  SaveHostCalibration(c, path);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find("1.31");
  ASSERT_NE(at, std::string::npos) << text;
  text.replace(at, 4, "-2");
  std::ofstream(path) << text;
  try {
    LoadHostCalibration(path);
    FAIL() << "a negative probe speed was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("probe_speed"), std::string::npos) << e.what();
  }
}

TEST_F(HostCalibrationTest, ValidWhenCpuAndReferenceMatch) {
  const std::string path = Path("c.json");
  SaveHostCalibration(Sample(), path);
  const CalibrationCheck check = CheckHostCalibration(path, "Test CPU 9000", "ref-1");
  EXPECT_TRUE(check.ok()) << check.message;
  ASSERT_TRUE(check.calibration.has_value());
}

TEST_F(HostCalibrationTest, MissingFileNamesTheCommandThatFixesIt) {
  const CalibrationCheck check = CheckHostCalibration(Path("nope.json"), "Test CPU 9000", "ref-1");
  EXPECT_EQ(check.status, CalibrationCheck::Status::kMissing);
  EXPECT_NE(check.message.find("enavi calibrate"), std::string::npos) << check.message;
  EXPECT_NE(check.message.find("nope.json"), std::string::npos) << check.message;
}

TEST_F(HostCalibrationTest, OtherCpuModelIsStale) {
  const std::string path = Path("c.json");
  SaveHostCalibration(Sample(), path);
  const CalibrationCheck check = CheckHostCalibration(path, "Another CPU", "ref-1");
  EXPECT_EQ(check.status, CalibrationCheck::Status::kStale);
  EXPECT_NE(check.message.find("Test CPU 9000"), std::string::npos) << check.message;
  EXPECT_NE(check.message.find("Another CPU"), std::string::npos) << check.message;
  EXPECT_NE(check.message.find("enavi calibrate"), std::string::npos) << check.message;
}

TEST_F(HostCalibrationTest, OtherReferenceCalibrationIsStale) {
  const std::string path = Path("c.json");
  SaveHostCalibration(Sample(), path);
  const CalibrationCheck check = CheckHostCalibration(path, "Test CPU 9000", "ref-2");
  EXPECT_EQ(check.status, CalibrationCheck::Status::kStale);
  EXPECT_NE(check.message.find("ref-2"), std::string::npos) << check.message;
}

TEST_F(HostCalibrationTest, CorruptFileIsInvalidWithTheFieldNamed) {
  const std::string path = Path("c.json");
  {
    std::ofstream out(path);
    out << R"({"format": "enavi-host-calibration", "version": 3, "relative_speed": -3})";
  }
  const CalibrationCheck check = CheckHostCalibration(path, "Test CPU 9000", "ref-1");
  EXPECT_EQ(check.status, CalibrationCheck::Status::kInvalid);
  EXPECT_NE(check.message.find("relative_speed"), std::string::npos) << check.message;
  {
    std::ofstream out(path);
    out << "not json";
  }
  EXPECT_THROW(LoadHostCalibration(path), std::invalid_argument);
}

// A file from before per-task overheads (version 1: one ns_per_job for all tasks) is refused,
// naming the file and the field, with the command that rewrites it.
TEST_F(HostCalibrationTest, FileWithOneOverheadForAllTasksIsRefusedNamingFileAndField) {
  const std::string path = Path("old.json");
  const std::string fitted = R"("fitted": {"ns_per_job": 0.0, "ns_per_unit": {}})";
  {
    std::ofstream out(path);
    out << R"({"format": "enavi-host-calibration", "version": 1, )" << fitted << "}";
  }
  const CalibrationCheck check = CheckHostCalibration(path, "Test CPU 9000", "ref-1");
  EXPECT_EQ(check.status, CalibrationCheck::Status::kInvalid);
  EXPECT_NE(check.message.find(path + ": version: is 1"), std::string::npos) << check.message;
  EXPECT_NE(check.message.find("enavi calibrate"), std::string::npos) << check.message;
  // The same fit under the current version number: the per-task field is named.
  SaveHostCalibration(Sample(), path);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"ns_per_job\": {");
  ASSERT_NE(at, std::string::npos) << text;
  text.replace(at, text.find('}', at) - at + 1, "\"ns_per_job\": 0.0");
  {
    std::ofstream out(path);
    out << text;
  }
  try {
    LoadHostCalibration(path);
    FAIL() << "a single ns_per_job must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": fitted.ego_planner.ns_per_job: expected an object"), std::string::npos)
        << e.what();
  }
}

TEST_F(HostCalibrationTest, PathPrecedenceFlagThenEnvThenXdgThenHome) {
  const char* saved[] = {std::getenv("ENAVI_CALIBRATION"), std::getenv("XDG_STATE_HOME"), std::getenv("HOME")};
  const std::string keep[] = {saved[0] ? saved[0] : "", saved[1] ? saved[1] : "", saved[2] ? saved[2] : ""};
  setenv("ENAVI_CALIBRATION", "/env/cal.json", 1);
  setenv("XDG_STATE_HOME", "/xdg", 1);
  setenv("HOME", "/home/u", 1);
  EXPECT_EQ(CalibrationPath("/flag.json"), "/flag.json");
  EXPECT_EQ(CalibrationPath(), "/env/cal.json");
  unsetenv("ENAVI_CALIBRATION");
  EXPECT_EQ(CalibrationPath(), "/xdg/enavi/calibration.json");
  unsetenv("XDG_STATE_HOME");
  EXPECT_EQ(CalibrationPath(), "/home/u/.local/state/enavi/calibration.json");
  const char* names[] = {"ENAVI_CALIBRATION", "XDG_STATE_HOME", "HOME"};
  for (int i = 0; i < 3; ++i) {
    if (saved[i]) {
      setenv(names[i], keep[i].c_str(), 1);
    } else {
      unsetenv(names[i]);
    }
  }
}

TEST(HostCalibrationSpeedTest, BoardSpeedIsRelativeToTheHostAndTheHostIsItself) {
  const double host = 2.0;  // a host twice the reference: every board is slower still
  EXPECT_DOUBLE_EQ(SpeedVsHost(LoadBoard("opi5"), host), 0.43);
  EXPECT_DOUBLE_EQ(SpeedVsHost(LoadBoard("host"), host), 1.0) << "the host is itself, whatever the calibration";
}

TEST(HostCalibrationSpeedTest, AProbeMovesTheCalibrationsSpeedByHowMuchTheProbeMoved) {
  HostCalibration host;
  host.relative_speed = 1.20;  // the full calibration plan's measure
  host.probe_speed = 1.25;     // the probe's, right after: its shorter flights weigh the work otherwise
  const SpeedDrift d = DriftSinceCalibration(host, 1.50);
  EXPECT_DOUBLE_EQ(d.at_calibration, 1.25);
  EXPECT_DOUBLE_EQ(d.ratio, 1.2);
  EXPECT_DOUBLE_EQ(d.host_speed, 1.44) << "the calibration's speed, moved by the probe's drift, not the probe's own";
  EXPECT_DOUBLE_EQ(SpeedVsHost(LoadBoard("opi5"), d.host_speed), 0.86 / 1.44);

  host.probe_speed = 0;  // a file written before the probe existed: compared with relative_speed
  EXPECT_DOUBLE_EQ(DriftSinceCalibration(host, 0.9).ratio, 0.75);
  EXPECT_DOUBLE_EQ(DriftSinceCalibration(host, 0.9).host_speed, 0.9);

  for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL})
    EXPECT_THROW(DriftSinceCalibration(host, bad), std::invalid_argument) << bad;
}

TEST(HostCalibrationSummaryTest, SummariseTimes) {
  std::vector<double> t;
  for (int i = 1; i <= 200; ++i) t.push_back(i * 0.001);
  const TaskTiming s = SummariseTimes(t);
  EXPECT_EQ(s.jobs, 200);
  EXPECT_DOUBLE_EQ(s.max_s, 0.2);
  EXPECT_DOUBLE_EQ(s.p99_s, 0.198);
  EXPECT_NEAR(s.mean_s, 0.1005, 1e-12);
  EXPECT_EQ(SummariseTimes({}).jobs, 0);
}

}  // namespace
}  // namespace enavi::board
