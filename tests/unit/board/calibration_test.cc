#include "workers/board/calibration.h"

#include <algorithm>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "navstack/methods/registry.h"
#include "navstack/runtime/cost_model.h"
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

const CoefficientFit& Named(const std::vector<CoefficientFit>& group, const std::string& name) {
  const auto it = std::find_if(group.begin(), group.end(), [&](const CoefficientFit& c) { return c.name == name; });
  if (it == group.end()) throw std::logic_error("no coefficient " + name);
  return *it;
}

// Uniform draws in [lo, hi) from a seeded engine: the tests' work counts and timing noise.
class Uniform {
 public:
  explicit Uniform(std::uint64_t seed) : rng_(seed) {}
  double operator()(double lo, double hi) { return lo + (hi - lo) * ((rng_() >> 11) * 0x1.0p-53); }

 private:
  std::mt19937_64 rng_;
};

TEST(CalibrationTest, FitRecoversPerUnitCostsAndPerTaskOverheadsFromNoisyJobs) {
  // Two tasks with different unit mixes and overheads (30 us a perception job, 5 us a planning
  // job), 3 % multiplicative timing noise; a tenth of the perception jobs find nothing to do.
  Uniform uniform(7);
  std::vector<JobSample> samples;
  for (int i = 0; i < 400; ++i) {
    JobSample s;
    s.task = i % 2 ? TaskId::kPerception : TaskId::kPlanning;
    double ns = 0;
    if (s.task == TaskId::kPerception) {
      if (i % 20 != 1) {
        s.work.Add(WorkUnit::kRayStep, static_cast<std::int64_t>(uniform(1e5, 3e5)));
        s.work.Add(WorkUnit::kVoxelUpdate, static_cast<std::int64_t>(uniform(1e4, 5e4)));
      }
      ns = 30e3;
    } else {
      s.work.Add(WorkUnit::kDistanceCell, static_cast<std::int64_t>(uniform(1e5, 9e5)));
      s.work.Add(WorkUnit::kStateCheck, static_cast<std::int64_t>(uniform(1e3, 2e4)));
      ns = 5e3;
    }
    ns += 17.0 * s.work.Get(WorkUnit::kRayStep) + 48.0 * s.work.Get(WorkUnit::kVoxelUpdate) +
          20.0 * s.work.Get(WorkUnit::kDistanceCell) + 150.0 * s.work.Get(WorkUnit::kStateCheck);
    s.host_cpu_s = ns * 1e-9 * uniform(0.97, 1.03);
    samples.push_back(s);
  }
  const CostFit fit = FitCosts(samples);
  const auto& c = fit.ns.ns_per_unit;
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kRayStep)], 17.0, 1.0);
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kVoxelUpdate)], 48.0, 4.0);
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kDistanceCell)], 20.0, 1.0);
  EXPECT_NEAR(c[static_cast<int>(WorkUnit::kStateCheck)], 150.0, 15.0);
  // The empty perception jobs pin the overhead; the 3 % noise of the full ones (150-400 us a
  // job, ten times the overhead) leaves it known to a quarter.
  EXPECT_NEAR(fit.ns.ns_per_job[static_cast<int>(TaskId::kPerception)], 30e3, 8e3);
  EXPECT_GT(fit.r2, 0.99);
  EXPECT_EQ(c[static_cast<int>(WorkUnit::kPixel)], 0.0);
  EXPECT_EQ(Named(fit.units, "pixel").zero_reason, "no job counted it");
  EXPECT_EQ(Named(fit.overheads, "eci").zero_reason, "no job of this task in the sample");
  EXPECT_EQ(Named(fit.units, "ray_step").jobs, 180);
  EXPECT_TRUE(Named(fit.units, "ray_step").zero_reason.empty());
  // Shares add up to the explained time; per-task figures cover every job.
  double share = 0;
  for (const auto* group : {&fit.units, &fit.overheads})
    for (const CoefficientFit& x : *group) share += x.share;
  EXPECT_NEAR(share, 1.0, 0.01);
  ASSERT_EQ(fit.per_task.size(), 2u);
  EXPECT_EQ(fit.per_task[0].task, "perception");
  EXPECT_EQ(fit.per_task[0].jobs, 200);
  EXPECT_GT(fit.per_task[0].r2, 0.99);
  EXPECT_NEAR(fit.per_task[1].relative_residual(), 0.0, 0.01);
  // A reference twice as slow per unit and per job: this host is 2x faster.
  ReferenceCosts slow;
  slow.families["navstack"] = fit.ns;
  for (double& v : slow.families["navstack"].ns_per_unit) v *= 2.0;
  for (double& v : slow.families["navstack"].ns_per_job) v *= 2.0;
  EXPECT_NEAR(RelativeSpeed(samples, slow), 2.0, 0.05);
}

TEST(CalibrationTest, ATaskWhoseJobsAllCountTheSameOfItsOwnUnitLeavesTheCostToTheUnit) {
  // Every eci job bins the same 76,800 pixels: its per-job column is the pixel column / 76,800.
  std::vector<JobSample> samples;
  for (int i = 0; i < 100; ++i) {
    JobSample eci;
    eci.task = TaskId::kEci;
    eci.work.Add(WorkUnit::kPixel, 76800);
    eci.host_cpu_s = (76800 * 0.6 + 2000) * 1e-9 * (1 + 0.01 * (i % 3));
    JobSample col;
    col.task = TaskId::kCollision;
    col.work.Add(WorkUnit::kCellProbe, 1000 + 37 * i);
    col.host_cpu_s = (9.0 * (1000 + 37 * i) + 4000) * 1e-9;
    samples.push_back(eci);
    samples.push_back(col);
  }
  const CostFit fit = FitCosts(samples);
  EXPECT_EQ(fit.ns.ns_per_job[static_cast<int>(TaskId::kEci)], 0.0);
  EXPECT_NEAR(fit.ns.ns_per_unit[static_cast<int>(WorkUnit::kPixel)], 0.6 + 2000.0 / 76800, 0.02);
  EXPECT_NE(Named(fit.overheads, "eci").zero_reason.find("not separable from pixel"), std::string::npos)
      << Named(fit.overheads, "eci").zero_reason;
  EXPECT_NEAR(fit.ns.ns_per_job[static_cast<int>(TaskId::kCollision)], 4000.0, 1.0);
  EXPECT_NEAR(fit.ns.ns_per_unit[static_cast<int>(WorkUnit::kCellProbe)], 9.0, 1e-3);
}

TEST(CalibrationTest, AZeroCoefficientSaysWhy) {
  // Collision jobs: cell probes cost 9 ns; trajectory samples always come 4 per probe (collinear
  // with them); the planning jobs' state checks cost nothing above noise.
  Uniform uniform(3);
  std::vector<JobSample> samples;
  for (int i = 0; i < 300; ++i) {
    JobSample s;
    s.task = TaskId::kCollision;
    const auto probes = static_cast<std::int64_t>(uniform(1e3, 1e5));
    s.work.Add(WorkUnit::kCellProbe, probes);
    s.work.Add(WorkUnit::kTrajectorySample, 4 * probes);
    s.host_cpu_s = 45.0 * probes * 1e-9 * uniform(0.98, 1.02);
    JobSample p;
    p.task = TaskId::kPlanning;
    const auto cells = static_cast<std::int64_t>(uniform(1e5, 1e6));
    p.work.Add(WorkUnit::kDistanceCell, cells);
    p.work.Add(WorkUnit::kStateCheck, static_cast<std::int64_t>(uniform(1, 100)));
    p.host_cpu_s = 20.0 * cells * 1e-9 * uniform(0.98, 1.02);
    samples.push_back(s);
    samples.push_back(p);
  }
  const CostFit fit = FitCosts(samples);
  const CoefficientFit& probe = Named(fit.units, "cell_probe");
  const CoefficientFit& sample = Named(fit.units, "trajectory_sample");
  // Exactly one of the pair carries the 45 ns per probe; the other is 0, collinear with it.
  ASSERT_TRUE((probe.ns == 0) != (sample.ns == 0)) << probe.ns << " " << sample.ns;
  const CoefficientFit& zero = probe.ns == 0 ? probe : sample;
  EXPECT_NE(zero.zero_reason.find("collinear with " + (probe.ns == 0 ? sample.name : probe.name)), std::string::npos)
      << zero.zero_reason;
  const CoefficientFit& check = Named(fit.units, "state_check");
  if (check.ns == 0) {
    EXPECT_NE(check.zero_reason.find("too small to see (free least squares gives"), std::string::npos)
        << check.zero_reason;
  } else {
    EXPECT_LT(check.ns, 2000.0) << "1-100 checks hidden in 2 % noise of 2-20 ms jobs";
  }
}

// The same unit at two prices in two code bases: one fit per family recovers each, and the
// reference that priced both alike shows up as opposite residuals of the two methods.
TEST(CalibrationTest, EachCostFamilyGetsItsOwnPricesAndAOnePriceReferenceShowsItsBias) {
  Uniform uniform(5);
  std::vector<JobSample> samples;
  for (int i = 0; i < 400; ++i) {
    JobSample s;
    s.task = TaskId::kPerception;
    const bool dense = i % 2 == 0;
    s.method = dense ? "baseline" : "fixed";
    s.family = dense ? "ego_planner" : "navstack";
    s.work.Add(WorkUnit::kRayStep, static_cast<std::int64_t>(uniform(1e4, 1e5)));
    s.work.Add(WorkUnit::kVoxelUpdate, static_cast<std::int64_t>(uniform(1e3, 2e4)));
    const double voxel_ns = dense ? 5.0 : 120.0;  // an array index against an octree descent
    s.host_cpu_s = (20e3 + 15.0 * s.work.Get(WorkUnit::kRayStep) + voxel_ns * s.work.Get(WorkUnit::kVoxelUpdate)) *
                   1e-9 * uniform(0.98, 1.02);
    samples.push_back(s);
  }
  const FamilyFits fits = FitCostFamilies(samples);
  ASSERT_EQ(fits.fits.size(), 2u);
  const int voxel = static_cast<int>(WorkUnit::kVoxelUpdate);
  EXPECT_NEAR(fits.costs.For("ego_planner").ns_per_unit[voxel], 5.0, 2.0);
  EXPECT_NEAR(fits.costs.For("navstack").ns_per_unit[voxel], 120.0, 5.0);
  EXPECT_GT(fits.r2, 0.99);
  EXPECT_EQ(fits.samples, 400);
  for (const auto& [family, fit] : fits.fits) {
    ASSERT_EQ(fit.per_method_task.size(), 1u) << family;
    EXPECT_NEAR(fit.per_method_task[0].relative_residual(), 0.0, 0.01) << family;
  }

  // One price for both (their mean), at this host's speed: the dense method is over-priced.
  ReferenceCosts one;
  one.families["ego_planner"] = fits.costs.For("navstack");
  one.families["ego_planner"].ns_per_unit[voxel] = 62.5;
  one.families["navstack"] = one.families["ego_planner"];
  const std::vector<TaskFitQuality> agreement = ReferenceAgreement(samples, one, RelativeSpeed(samples, one));
  ASSERT_EQ(agreement.size(), 2u);
  const TaskFitQuality& baseline = agreement[0].method == "baseline" ? agreement[0] : agreement[1];
  const TaskFitQuality& fixed = agreement[0].method == "baseline" ? agreement[1] : agreement[0];
  EXPECT_GT(baseline.relative_residual(), 0.2);
  EXPECT_LT(fixed.relative_residual(), -0.1);
  EXPECT_THROW(ReferenceAgreement(samples, one, 0.0), std::invalid_argument);
}

TEST(CalibrationTest, IdleJobsArePricedAtZeroAndDoNotPullTheOverheadOfJobsThatWork) {
  // Ego-Planner's FSM timer: 40 idle ticks (2 us, nothing counted) for every tick that plans
  // (67 us + its units). Fitted with the idle ticks, the per-job overhead would fall towards
  // their 2 us and the planning jobs would be under-priced; priced at the overhead, the ticks
  // would cost 33x their time.
  Uniform uniform(11);
  std::vector<JobSample> samples;
  for (int i = 0; i < 4100; ++i) {
    JobSample s;
    s.task = TaskId::kPlanning;
    s.method = "baseline";
    s.family = "ego_planner";
    if (i % 41 == 0) {
      s.work.Add(WorkUnit::kAstarExpansion, static_cast<std::int64_t>(uniform(1e2, 2e3)));
      s.work.Add(WorkUnit::kOptimizerEval, static_cast<std::int64_t>(uniform(1e3, 1e4)));
      s.host_cpu_s = (67e3 + 900.0 * s.work.Get(WorkUnit::kAstarExpansion) +
                      40.0 * s.work.Get(WorkUnit::kOptimizerEval)) * 1e-9 * uniform(0.995, 1.005);
    } else {
      s.host_cpu_s = 2e-6 * uniform(0.9, 1.1);
    }
    samples.push_back(s);
  }
  const FamilyFits fits = FitCostFamilies(samples);
  EXPECT_EQ(fits.samples, 4100);
  EXPECT_EQ(fits.idle, 4000);
  const ReferenceCosts::Coefficients& c = fits.costs.For("ego_planner");
  EXPECT_NEAR(c.ns_per_job[static_cast<int>(TaskId::kPlanning)], 67e3, 67e3 * 0.05);
  const navstack::WorkCountCostModel model(c);
  EXPECT_EQ(model.JobSeconds(TaskId::kPlanning, samples[1].work, 0.0), 0.0) << "an idle tick";
  EXPECT_NEAR(model.JobSeconds(TaskId::kPlanning, samples[0].work, 0.0), samples[0].host_cpu_s,
              samples[0].host_cpu_s * 0.05);
  double measured = 0, priced = 0;
  for (const JobSample& s : samples) {
    measured += s.host_cpu_s;
    priced += model.JobSeconds(s.task, s.work, 0.0);
  }
  EXPECT_NEAR(priced / measured, 1.0, 0.15) << "the ticks' 8 ms of 4000 x 2 us is all the model leaves out";
}

TEST(CalibrationTest, ANewCostFamilyIsCalibratedAgainstAReferenceThatDoesNotPriceItYet) {
  // The reference prices `navstack` only; this host runs its work at half the reference core's
  // speed. A code base flown here for the first time (`newstack`) must not stop the speed from
  // being measured on the work the reference knows, nor enter the reference's agreement table.
  ReferenceCosts reference;
  reference.calibration_id = "ref-1";
  ReferenceCosts::Coefficients known;
  known.ns_per_job[static_cast<int>(TaskId::kPerception)] = 20e3;
  known.ns_per_unit[static_cast<int>(WorkUnit::kRayStep)] = 15.0;
  reference.families["navstack"] = known;

  Uniform uniform(7);
  std::vector<JobSample> samples;
  for (int i = 0; i < 200; ++i) {
    JobSample s;
    s.task = TaskId::kPerception;
    const bool fresh = i % 2 == 0;
    s.method = fresh ? "newmethod" : "fixed";
    s.family = fresh ? "newstack" : "navstack";
    s.work.Add(WorkUnit::kRayStep, static_cast<std::int64_t>(uniform(1e4, 1e5)));
    const double ray_ns = fresh ? 90.0 : 15.0;
    s.host_cpu_s = 2.0 * (20e3 + ray_ns * s.work.Get(WorkUnit::kRayStep)) * 1e-9 * uniform(0.99, 1.01);
    samples.push_back(s);
  }
  EXPECT_EQ(UnpricedFamilies(samples, reference), std::vector<std::string>{"newstack"});
  const double speed = RelativeSpeed(samples, reference);
  EXPECT_NEAR(speed, 0.5, 0.01);
  const std::vector<TaskFitQuality> agreement = ReferenceAgreement(samples, reference, speed);
  ASSERT_EQ(agreement.size(), 1u);
  EXPECT_EQ(agreement[0].method, "fixed");
  EXPECT_NEAR(agreement[0].relative_residual(), 0.0, 0.02);
  // The fit prices both families; the new one at its own cost.
  const FamilyFits fits = FitCostFamilies(samples);
  EXPECT_NEAR(fits.costs.For("newstack").ns_per_unit[static_cast<int>(WorkUnit::kRayStep)], 180.0, 5.0);

  // A reference that prices none of the flown families cannot give a speed, and says why.
  std::vector<JobSample> only_new;
  for (const JobSample& s : samples)
    if (s.family == "newstack") only_new.push_back(s);
  try {
    RelativeSpeed(only_new, reference);
    FAIL() << "no priced work, yet a speed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("newstack"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("known: navstack"), std::string::npos) << e.what();
  }
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
    EXPECT_EQ(std::string(e.what()), "x.yaml:6: per_core_speed.value: must be > 0.0 (got -1)");
  }
  try {
    ParseBoardProfile("id: x\nname: X\ncpu: c\ncores: 4\ncors: 8\nper_core_speed:\n  value: 1\n", "x.yaml");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x.yaml:5: cors: unknown key"), std::string::npos) << e.what();
  }
}

TEST(BoardProfileTest, ReferenceCostsInAnOldFormatOrWithAMissingTaskNameFileAndField) {
  const std::string one_set = "reference_cpu: \"X\"\ncalibration_id: \"1\"\nns_per_job:\n  perception: 1.0\n";
  try {
    ParseReferenceCosts(one_set, "ref.yaml");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ref.yaml:4: ns_per_job: one set of prices for every method is the format "
                                         "before cost families"),
              std::string::npos)
        << e.what();
  }
  const std::string one_overhead =
      "reference_cpu: \"X\"\ncalibration_id: \"1\"\nfamilies:\n  navstack:\n    ns_per_job: 0.0\n    ns_per_unit: {}\n";
  try {
    ParseReferenceCosts(one_overhead, "ref.yaml");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ref.yaml:5: families.navstack.ns_per_job: must map each task"),
              std::string::npos)
        << e.what();
  }
  const std::string missing_task =
      "reference_cpu: \"X\"\ncalibration_id: \"1\"\nfamilies:\n  navstack:\n    ns_per_job:\n      perception: 1.0\n"
      "    ns_per_unit:\n      pixel: 0.5\n";
  try {
    ParseReferenceCosts(missing_task, "ref.yaml");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("families.navstack.ns_per_job.planning: missing"), std::string::npos)
        << e.what();
  }
}

TEST(BoardProfileTest, TheReferenceCostsFileReadsBackWhatTheFitWrites) {
  ReferenceCosts costs;
  costs.reference_cpu = "AMD EPYC";
  costs.calibration_id = "42-7";
  costs.families["navstack"].ns_per_job[static_cast<int>(TaskId::kAdapter)] = 1234.5;
  costs.families["navstack"].ns_per_unit[static_cast<int>(WorkUnit::kRayStep)] = 18.25;
  costs.families["ego_planner"].ns_per_unit[static_cast<int>(WorkUnit::kRayStep)] = 9.5;
  const ReferenceCosts back = ParseReferenceCosts(ReferenceCostsYaml(costs, "two\nlines"), "written.yaml");
  EXPECT_EQ(back.calibration_id, "42-7");
  ASSERT_EQ(back.families.size(), 2u);
  for (const auto& [family, c] : costs.families) {
    EXPECT_EQ(back.For(family).ns_per_job, c.ns_per_job) << family;
    EXPECT_EQ(back.For(family).ns_per_unit, c.ns_per_unit) << family;
  }
}

TEST(BoardProfileTest, AMethodOfAnUnpricedCostFamilyIsRefusedByName) {
  ReferenceCosts ref;
  ref.calibration_id = "42-7";
  ref.families["navstack"] = {};
  try {
    ref.For("rust_planner");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no prices for cost family 'rust_planner' (known: navstack)"), std::string::npos)
        << e.what();
  }
}

TEST(BoardProfileTest, EveryRegisteredMethodsCostFamilyIsPricedByTheEmbeddedReference) {
  const ReferenceCosts ref = LoadReferenceCosts();
  for (const navstack::MethodInfo& m : navstack::Methods()) EXPECT_NO_THROW(ref.For(m.cost_family)) << m.name;
  // Ego-Planner's node is other code than our stack: it has prices of its own.
  EXPECT_EQ(navstack::FindMethod("baseline")->cost_family, "ego_planner");
  EXPECT_EQ(navstack::FindMethod("enavi")->cost_family, navstack::FindMethod("fixed")->cost_family);
  EXPECT_NE(ref.For("ego_planner").ns_per_unit, ref.For("navstack").ns_per_unit);
}

TEST(BoardProfileTest, CoefficientsScaleWithPerCoreSpeed) {
  ReferenceCosts ref;
  ref.families["navstack"].ns_per_unit[static_cast<int>(WorkUnit::kRayStep)] = 10.0;
  ref.families["navstack"].ns_per_job[static_cast<int>(TaskId::kPlanning)] = 3000.0;
  BoardProfile b;
  b.per_core_speed = 0.5;
  EXPECT_DOUBLE_EQ(BoardCoefficients(b, ref, "navstack").ns_per_unit[static_cast<int>(WorkUnit::kRayStep)], 20.0);
  EXPECT_DOUBLE_EQ(BoardCoefficients(b, ref, "navstack").ns_per_job[static_cast<int>(TaskId::kPlanning)], 6000.0);
}

}  // namespace
}  // namespace enavi::board
