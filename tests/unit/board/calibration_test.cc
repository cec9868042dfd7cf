#include "workers/board/calibration.h"

#include <random>

#include <gtest/gtest.h>

#include "workers/board/nnls.h"

namespace enavi::board {
namespace {

using navstack::TaskId;
using navstack::WorkUnit;

TEST(NnlsTest, MatchesUnconstrainedSolutionWhenItIsPositive) {
  Eigen::MatrixXd A(4, 2);
  A << 1, 0, 0, 1, 1, 1, 2, 1;
  const Eigen::Vector2d x_true(2.0, 3.0);
  const NnlsResult r = SolveNnls(A, A * x_true);
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(r.x[0], 2.0, 1e-9);
  EXPECT_NEAR(r.x[1], 3.0, 1e-9);
}

TEST(NnlsTest, ClampsANegativeCoefficientToZero) {
  // Unconstrained least squares would give x1 < 0; NNLS keeps it at 0 and refits x0.
  Eigen::MatrixXd A(3, 2);
  A << 1, 1, 1, 2, 1, 3;
  const Eigen::Vector3d b(3, 2, 1);
  const NnlsResult r = SolveNnls(A, b);
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.x[1], 0.0);
  EXPECT_NEAR(r.x[0], 2.0, 1e-9) << "mean of b";
}

TEST(CalibrationTest, FitRecoversPerUnitCostsFromNoisyJobs) {
  // Two tasks with different unit mixes, 3 % multiplicative timing noise.
  std::mt19937_64 rng(7);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * ((rng() >> 11) * 0x1.0p-53); };
  std::vector<JobSample> samples;
  for (int i = 0; i < 400; ++i) {
    JobSample s;
    s.task = i % 2 ? TaskId::kPerception : TaskId::kPlanning;
    if (s.task == TaskId::kPerception) {
      s.work.Add(WorkUnit::kRayStep, static_cast<std::int64_t>(uniform(1e5, 3e5)));
      s.work.Add(WorkUnit::kVoxelUpdate, static_cast<std::int64_t>(uniform(1e4, 5e4)));
    } else {
      s.work.Add(WorkUnit::kDistanceCell, static_cast<std::int64_t>(uniform(1e5, 9e5)));
      s.work.Add(WorkUnit::kStateCheck, static_cast<std::int64_t>(uniform(1e3, 2e4)));
    }
    const double ns = 17.0 * s.work.Get(WorkUnit::kRayStep) + 48.0 * s.work.Get(WorkUnit::kVoxelUpdate) +
                      20.0 * s.work.Get(WorkUnit::kDistanceCell) + 150.0 * s.work.Get(WorkUnit::kStateCheck);
    s.host_cpu_s = ns * 1e-9 * uniform(0.97, 1.03);
    samples.push_back(s);
  }
  const CostFit fit = FitCosts(samples);
  const auto& c = fit.costs.ns.ns_per_unit;
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kRayStep)], 17.0, 1.0);
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kVoxelUpdate)], 48.0, 4.0);
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kDistanceCell)], 20.0, 1.0);
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kStateCheck)], 150.0, 15.0);
  EXPECT_GT(fit.r2, 0.99);
  EXPECT_EQ(c[static_cast<int>(WorkUnit::kPixel)], 0.0);
  EXPECT_NE(std::find(fit.unobserved_units.begin(), fit.unobserved_units.end(), "pixel"), fit.unobserved_units.end());
  // A reference twice as slow per unit: this host is 2x faster.
  ReferenceCosts slow = fit.costs;
  for (double& v : slow.ns.ns_per_unit) v *= 2.0;
  EXPECT_NEAR(RelativeSpeed(samples, slow), 2.0, 0.05);
}

TEST(CalibrationTest, TooFewSamplesIsAnError) {
  EXPECT_THROW(FitCosts({JobSample{}}), std::invalid_argument);
}

TEST(BoardProfileTest, EveryEmbeddedBoardLoadsWithACitedSpeed) {
  const auto boards = KnownBoards();
  ASSERT_FALSE(boards.empty());
  for (const auto& id : boards) {
    const BoardProfile b = LoadBoard(id);
    EXPECT_EQ(b.id, id);
    EXPECT_GT(b.cores, 0);
    EXPECT_GT(b.per_core_speed, 0.1) << id;
    EXPECT_LE(b.per_core_speed, 1.0) << id << ": no board is faster than the reference host";
    EXPECT_FALSE(b.speed_benchmark.empty()) << id;
  }
  EXPECT_EQ(LoadBoard("pi4b").cores, 4);
  EXPECT_EQ(LoadBoard("nx").cores, 6);
  EXPECT_TRUE(LoadBoard("host").is_host);
}

TEST(BoardProfileTest, UnknownBoardNamesTheKnownOnes) {
  try {
    LoadBoard("pi5");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pi5"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("tx2"), std::string::npos);
  }
}

TEST(BoardProfileTest, BadProfileNamesFileLineAndField) {
  const std::string text = "id: x\nname: X\ncpu: c\ncores: 4\nper_core_speed:\n  value: -1\n";
  try {
    ParseBoardProfile(text, "x.yaml");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x.yaml:6: value"), std::string::npos) << e.what();
  }
}

TEST(BoardProfileTest, CoefficientsScaleWithPerCoreSpeed) {
  ReferenceCosts ref;
  ref.ns.ns_per_unit[static_cast<int>(WorkUnit::kRayStep)] = 10.0;
  BoardProfile b;
  b.per_core_speed = 0.5;
  EXPECT_DOUBLE_EQ(BoardCoefficients(b, ref).ns_per_unit[static_cast<int>(WorkUnit::kRayStep)], 20.0);
}

}  // namespace
}  // namespace enavi::board
