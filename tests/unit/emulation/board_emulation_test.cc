// How a board is emulated on a calibrated host: the figures `enavi calibrate` prints.
#include "workers/emulation/board_emulation.h"

#include <gtest/gtest.h>

namespace enavi::emulation {
namespace {

board::HostCalibration Host(double relative_speed) {
  board::HostCalibration c;
  c.relative_speed = relative_speed;
  c.tasks["perception"] = {100, 0.010, 0.020, 0.025};
  c.tasks["planning"] = {50, 0.020, 0.040, 0.050};
  return c;
}

TEST(BoardEmulationTest, BoardEmulationFigures) {
  const BoardEmulation pi = DescribeBoardEmulation(board::LoadBoard("pi4b"), Host(1.0), 1.75);
  EXPECT_EQ(pi.cores, 4);
  EXPECT_DOUBLE_EQ(pi.speed_vs_host, 0.56);
  EXPECT_DOUBLE_EQ(pi.quota_cpus_k1, 4 * 0.56);
  EXPECT_DOUBLE_EQ(pi.min_dilation, 1.5) << "2.24 CPUs need k >= 1.28, rounded up to a quarter";
  EXPECT_NEAR(pi.wcet_s.at("planning"), 0.050 / 0.56, 1e-12) << "host WCET / board speed";

  // A host twice the reference: every board is slower still.
  EXPECT_DOUBLE_EQ(DescribeBoardEmulation(board::LoadBoard("opi5"), Host(2.0), 1.75).speed_vs_host, 0.43);
  // A board faster than the host: time dilated at least by its speed, whatever the host has free.
  const BoardEmulation fast = DescribeBoardEmulation(board::LoadBoard("opi5"), Host(0.5), 16.0);
  EXPECT_DOUBLE_EQ(fast.speed_vs_host, 0.86 / 0.5);
  EXPECT_DOUBLE_EQ(fast.min_dilation, 1.75) << "speed 1.72, rounded up to a quarter";
}

}  // namespace
}  // namespace enavi::emulation
