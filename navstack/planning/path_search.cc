#include "navstack/planning/path_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <utility>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateSampler.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/datastructures/NearestNeighborsGNATNoThreadSafety.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

namespace enavi::navstack {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using Vec3 = Eigen::Vector3d;

// ---------------------------------------------------------------------------------------------
// OMPL console routing (process-wide, as OMPL's console is).

class SinkOutputHandler : public ompl::msg::OutputHandler {
 public:
  void log(const std::string& text, ompl::msg::LogLevel level, const char*, int) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!sink_) return;
    OmplLogLevel l = OmplLogLevel::kDebug;
    if (level == ompl::msg::LOG_INFO) l = OmplLogLevel::kInfo;
    if (level == ompl::msg::LOG_WARN) l = OmplLogLevel::kWarn;
    if (level == ompl::msg::LOG_ERROR) l = OmplLogLevel::kError;
    sink_(l, text);
  }
  void set_sink(OmplLogSink sink) {
    std::lock_guard<std::mutex> lock(mutex_);
    sink_ = std::move(sink);
  }

 private:
  std::mutex mutex_;
  OmplLogSink sink_;
};

std::mutex g_log_mutex;
bool g_log_configured = false;  // guarded by g_log_mutex

SinkOutputHandler& LogHandler() {
  static SinkOutputHandler* handler = new SinkOutputHandler();  // lives as long as OMPL may log
  return *handler;
}

// OMPL prints Info/Debug to stdout by default; unless routed, keep only warnings and errors.
void EnsureOmplLogConfigured() {
  std::lock_guard<std::mutex> lock(g_log_mutex);
  if (g_log_configured) return;
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  g_log_configured = true;
}

// ---------------------------------------------------------------------------------------------
// OMPL adapters: sampler with its own seed, clearance validity, stepped motion checks.

Vec3 ToVec(const ob::State* s) {
  const double* v = s->as<ob::RealVectorStateSpace::StateType>()->values;
  return {v[0], v[1], v[2]};
}

// Uniform sampler whose RNG is seeded per search (OMPL's global seed can be set only once per
// process); it counts the samples drawn, which is RRT-Connect's iteration count.
class SeededSampler : public ob::StateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed, std::int64_t* samples)
      : ob::StateSampler(space),
        bounds_(space->as<ob::RealVectorStateSpace>()->getBounds()),
        samples_(samples) {
    rng_.setLocalSeed(seed);
  }
  void sampleUniform(ob::State* state) override {
    double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    for (int i = 0; i < 3; ++i) v[i] = rng_.uniformReal(bounds_.low[i], bounds_.high[i]);
    ++*samples_;
  }
  void sampleUniformNear(ob::State* state, const ob::State* near, double distance) override {
    double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    const double* c = near->as<ob::RealVectorStateSpace::StateType>()->values;
    for (int i = 0; i < 3; ++i) {
      v[i] = rng_.uniformReal(std::max(bounds_.low[i], c[i] - distance),
                              std::min(bounds_.high[i], c[i] + distance));
    }
  }
  void sampleGaussian(ob::State* state, const ob::State* mean, double std_dev) override {
    double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    const double* c = mean->as<ob::RealVectorStateSpace::StateType>()->values;
    for (int i = 0; i < 3; ++i) {
      v[i] = std::clamp(rng_.gaussian(c[i], std_dev), bounds_.low[i], bounds_.high[i]);
    }
  }

 private:
  ob::RealVectorBounds bounds_;
  std::int64_t* samples_;
};

class ClearanceValidityChecker : public ob::StateValidityChecker {
 public:
  ClearanceValidityChecker(const ob::SpaceInformationPtr& si, const ClearanceMap& map,
                           const ClearanceRule& rule, std::int64_t* checks)
      : ob::StateValidityChecker(si), map_(map), rule_(rule), checks_(checks) {}
  bool isValid(const ob::State* state) const override {
    ++*checks_;
    const Vec3 p = ToVec(state);
    return map_.IsClear(p, rule_.RequiredAt(p));
  }

 private:
  const ClearanceMap& map_;
  const ClearanceRule& rule_;
  std::int64_t* checks_;
};

// Number of steps of a motion check of segment a-b.
int MotionSteps(const Vec3& a, const Vec3& b, double step) {
  return std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
}

// Index 1..n of the first point of a-b (a excluded) that violates rule; n + 1 if none does.
int FirstInvalidStep(const ClearanceMap& map, const ClearanceRule& rule, const Vec3& a,
                     const Vec3& b, int n, std::int64_t* checks) {
  for (int i = 1; i <= n; ++i) {
    const Vec3 p = a + (b - a) * (static_cast<double>(i) / n);
    ++*checks;
    if (!map.IsClear(p, rule.RequiredAt(p))) return i;
  }
  return n + 1;
}

class SteppedMotionValidator : public ob::MotionValidator {
 public:
  SteppedMotionValidator(const ob::SpaceInformationPtr& si, const ClearanceMap& map,
                         const ClearanceRule& rule, double step, std::int64_t* checks)
      : ob::MotionValidator(si), map_(map), rule_(rule), step_(step), checks_(checks) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    const Vec3 a = ToVec(s1), b = ToVec(s2);
    const int n = MotionSteps(a, b, step_);
    const bool ok = FirstInvalidStep(map_, rule_, a, b, n, checks_) > n;
    ok ? ++valid_ : ++invalid_;
    return ok;
  }
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    const Vec3 a = ToVec(s1), b = ToVec(s2);
    const int n = MotionSteps(a, b, step_);
    const int bad = FirstInvalidStep(map_, rule_, a, b, n, checks_);
    if (bad > n) {
      ++valid_;
      return true;
    }
    last_valid.second = static_cast<double>(bad - 1) / n;
    if (last_valid.first != nullptr) {
      si_->getStateSpace()->interpolate(s1, s2, last_valid.second, last_valid.first);
    }
    ++invalid_;
    return false;
  }

 private:
  const ClearanceMap& map_;
  const ClearanceRule& rule_;
  double step_;
  std::int64_t* checks_;
};

// Largest t in [0, 1] with a + t (b - a) inside box (a inside box).
double ExitParameter(const Vec3& a, const Vec3& b, const Eigen::AlignedBox3d& box) {
  double t = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double d = b[k] - a[k];
    if (d > 0.0) t = std::min(t, (box.max()[k] - a[k]) / d);
    if (d < 0.0) t = std::min(t, (box.min()[k] - a[k]) / d);
  }
  return std::clamp(t, 0.0, 1.0);
}

double Step(const ClearanceMap& map, const PlannerOptions& options) {
  return options.motion_check_fraction * map.resolution();
}

std::vector<Vec3> GreedyShortcut(const std::vector<Vec3>& path, const ClearanceMap& map,
                                 const ClearanceRule& rule, const PlannerOptions& options,
                                 WorkCounts* work) {
  if (path.size() <= 2) return path;
  std::vector<Vec3> out{path.front()};
  std::size_t i = 0;
  while (i + 1 < path.size()) {
    // Extend the jump from vertex i while the straight segment stays free.
    std::size_t j = i + 1;
    while (j + 1 < path.size() && SegmentIsFree(map, rule, path[i], path[j + 1], options, work)) {
      ++j;
    }
    out.push_back(path[j]);
    i = j;
  }
  return out;
}

}  // namespace

void RouteOmplLog(OmplLogSink sink, OmplLogLevel min_level) {
  std::lock_guard<std::mutex> lock(g_log_mutex);
  if (sink) {
    LogHandler().set_sink(std::move(sink));
    ompl::msg::useOutputHandler(&LogHandler());
  } else {
    LogHandler().set_sink(nullptr);
    ompl::msg::noOutputHandler();
  }
  static constexpr ompl::msg::LogLevel kLevels[] = {ompl::msg::LOG_DEBUG, ompl::msg::LOG_INFO,
                                                    ompl::msg::LOG_WARN, ompl::msg::LOG_ERROR};
  ompl::msg::setLogLevel(kLevels[static_cast<int>(min_level)]);
  g_log_configured = true;
}

ClearanceRule MakeClearanceRule(const ClearanceMap& map, const Vec3& p_start,
                                const PlannerOptions& options) {
  ClearanceRule rule;
  rule.required = options.robot_radius + options.search_margin;
  rule.escape_center = p_start;
  double c0 = map.Clearance(p_start, rule.required);
  // The map's validity test may be stricter than its exact clearance (InflatedOccupancy's cube
  // test near a corner): relax to the largest clearance the test itself accepts at the start, or
  // the search would refuse a start the escape ball was not made for.
  const double res = map.resolution();
  while (c0 > 0.0 && !map.IsClear(p_start, std::min(c0, rule.required))) c0 -= res;
  if (c0 < rule.required) {
    rule.escape_radius = (rule.required - std::max(c0, 0.0)) + 2.0 * res;
    rule.escape_required = c0 - 0.5 * res;
  }
  return rule;
}

Eigen::AlignedBox3d PlanningVolume(const Vec3& start, const Vec3& goal,
                                   const Eigen::AlignedBox3d& flight_bounds,
                                   const PlannerOptions& options) {
  const double width = options.camera_range + options.volume_back_margin;
  const double height = options.volume_height;
  // Horizontal centre: start moved towards the goal so that the start sits volume_back_margin
  // from the back of the box, or half-way to a nearer goal.
  Eigen::Vector2d dir = (goal - start).head<2>();
  const double dist_xy = dir.norm();
  Eigen::Vector2d centre_xy = start.head<2>();
  if (dist_xy > 1e-9) {
    dir /= dist_xy;
    const double offset = std::min(0.5 * width - options.volume_back_margin, 0.5 * dist_xy);
    centre_xy += std::max(offset, 0.0) * dir;
  }
  const Vec3 centre(centre_xy.x(), centre_xy.y(), 0.5 * (start.z() + goal.z()));
  const Vec3 half(0.5 * width, 0.5 * width, 0.5 * height);
  Eigen::AlignedBox3d box(centre - half, centre + half);
  // Inside the flight bounds: shift along an axis where the box fits, clip where it does not.
  if (!flight_bounds.isEmpty()) {
    for (int k = 0; k < 3; ++k) {
      const double lo = flight_bounds.min()[k], hi = flight_bounds.max()[k];
      if (box.max()[k] - box.min()[k] <= hi - lo) {
        double shift = 0.0;
        if (box.min()[k] < lo) shift = lo - box.min()[k];
        if (box.max()[k] > hi) shift = hi - box.max()[k];
        box.min()[k] += shift;
        box.max()[k] += shift;
      } else {
        box.min()[k] = lo;
        box.max()[k] = hi;
      }
    }
  }
  return box;
}

Eigen::AlignedBox3d SearchBounds(const ClearanceMap& map,
                                 const Eigen::AlignedBox3d& flight_bounds,
                                 const PlannerOptions& options) {
  Eigen::AlignedBox3d b = map.Box().intersection(flight_bounds);
  b.min().z() = std::max(b.min().z(), options.min_altitude);
  if (b.isEmpty()) return b;
  const Vec3 eps = Vec3::Constant(1e-6);
  return {b.min() + eps, b.max() - eps};
}

bool SegmentIsFree(const ClearanceMap& map, const ClearanceRule& rule, const Vec3& a,
                   const Vec3& b, const PlannerOptions& options, WorkCounts* work) {
  const int n = MotionSteps(a, b, Step(map, options));
  std::int64_t checks = 0;
  const bool ok = FirstInvalidStep(map, rule, a, b, n, &checks) > n;
  if (work != nullptr) work->Add(WorkUnit::kStateCheck, checks);
  return ok;
}

std::vector<Vec3> ShortcutPath(const std::vector<Vec3>& path, const ClearanceMap& map,
                               const ClearanceRule& rule, const PlannerOptions& options,
                               WorkCounts* work) {
  std::vector<Vec3> coarse = GreedyShortcut(path, map, rule, options, work);
  // Densify so the second pass can also cut corners between the first pass' vertices.
  std::vector<Vec3> dense{coarse.front()};
  for (std::size_t i = 1; i < coarse.size(); ++i) {
    const int n = std::max(
        1, static_cast<int>(std::ceil((coarse[i] - coarse[i - 1]).norm() / options.shortcut_spacing)));
    for (int k = 1; k <= n; ++k) {
      dense.push_back(coarse[i - 1] + (coarse[i] - coarse[i - 1]) * (static_cast<double>(k) / n));
    }
  }
  return GreedyShortcut(dense, map, rule, options, work);
}

PathSearchResult SearchPath(const ClearanceMap& map, const Eigen::AlignedBox3d& bounds,
                            const ClearanceRule& rule, const Vec3& start, const Vec3& goal,
                            std::uint32_t seed, const PlannerOptions& options, WorkCounts* work,
                            const OverBudget& over_budget) {
  EnsureOmplLogConfigured();
  PathSearchResult result;
  std::int64_t checks = 0;
  const auto is_valid = [&](const Vec3& p) {
    ++checks;
    const double required = rule.RequiredAt(p);
    return map.IsClear(p, required);
  };
  const auto finish = [&](SearchStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    if (work != nullptr) {
      work->Add(WorkUnit::kStateCheck, checks);
      work->Add(WorkUnit::kPlannerIteration, result.iterations);
    }
    return result;
  };
  if (bounds.isEmpty() || !bounds.contains(start) || !is_valid(start)) {
    return finish(SearchStatus::kInvalidStart, "start outside the search bounds or too close to obstacles");
  }
  if (!bounds.contains(goal) || !is_valid(goal)) {
    return finish(SearchStatus::kInvalidGoal, "goal outside the search bounds or too close to obstacles");
  }

  // Straight line first: the common case in open space costs no search at all.
  if (SegmentIsFree(map, rule, start, goal, options, work)) {
    result.path = {start, goal};
    return finish(SearchStatus::kOk, "straight line");
  }

  // RRT-Connect in a 3-D box. Everything random comes from the seeded sampler; nearest
  // neighbours are linear (OMPL's default GNAT draws its pivots from an unseeded RNG, which
  // could change tie-breaking); termination is on the sample count, never on wall time.
  auto space = std::make_shared<ob::RealVectorStateSpace>(3);
  ob::RealVectorBounds rb(3);
  for (int k = 0; k < 3; ++k) {
    rb.setLow(k, bounds.min()[k]);
    rb.setHigh(k, bounds.max()[k]);
  }
  space->setBounds(rb);
  std::int64_t samples = 0;
  space->setStateSamplerAllocator([seed, &samples](const ob::StateSpace* s) -> ob::StateSamplerPtr {
    return std::make_shared<SeededSampler>(s, seed, &samples);
  });
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker(std::make_shared<ClearanceValidityChecker>(si, map, rule, &checks));
  si->setMotionValidator(
      std::make_shared<SteppedMotionValidator>(si, map, rule, Step(map, options), &checks));
  si->setup();

  ob::ScopedState<ob::RealVectorStateSpace> s_start(space), s_goal(space);
  for (int k = 0; k < 3; ++k) {
    s_start[k] = start[k];
    s_goal[k] = goal[k];
  }
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->setStartAndGoalStates(s_start, s_goal);

  auto planner = std::make_shared<og::RRTConnect>(si);
  planner->setRange(options.search_range);
  planner->setProblemDefinition(pdef);
  // GNAT (OMPL's default for RRT-Connect) is an exact nearest-neighbour search, so the trees
  // grow as with a linear scan; a linear scan made a failing 5000-sample search quadratic.
  planner->setNearestNeighbors<ompl::NearestNeighborsGNATNoThreadSafety>();  // also runs setup()

  // Termination on the sample count or, if a budget hook is set, on the work done so far (the
  // counts this search has not yet added to *work included).
  const std::int64_t budget = options.max_search_iterations;
  bool over = false;
  const ob::PlannerTerminationCondition ptc([&] {
    if (samples >= budget) return true;
    if (over_budget) {
      WorkCounts now = work != nullptr ? *work : WorkCounts{};
      now.Add(WorkUnit::kStateCheck, checks);
      now.Add(WorkUnit::kPlannerIteration, samples);
      over = over_budget(now);
    }
    return over;
  });
  const ob::PlannerStatus status = planner->solve(ptc);
  result.iterations = static_cast<int>(samples);
  if (over && status != ob::PlannerStatus::EXACT_SOLUTION) {
    std::ostringstream msg;
    msg << "RRT-Connect stopped by the work budget after " << samples << " iterations";
    return finish(SearchStatus::kOverBudget, msg.str());
  }
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    std::ostringstream msg;
    msg << "RRT-Connect found no path in " << samples << " iterations (" << status.asString() << ")";
    return finish(SearchStatus::kNoPath, msg.str());
  }
  const auto* geometric = pdef->getSolutionPath()->as<og::PathGeometric>();
  std::vector<Vec3> raw;
  raw.reserve(geometric->getStateCount());
  for (std::size_t i = 0; i < geometric->getStateCount(); ++i) raw.push_back(ToVec(geometric->getState(i)));
  // The solution's end points are copies of ours; keep ours bit-exact.
  raw.front() = start;
  raw.back() = goal;

  WorkCounts shortcut_work;
  result.path = ShortcutPath(raw, map, rule, options, &shortcut_work);
  checks += shortcut_work.Get(WorkUnit::kStateCheck);
  std::ostringstream msg;
  msg << "RRT-Connect: " << samples << " iterations, " << raw.size() << " states, "
      << result.path.size() << " after shortcut";
  return finish(SearchStatus::kOk, msg.str());
}

std::vector<Vec3> GoalCandidates(const ClearanceMap& map, const Eigen::AlignedBox3d& bounds,
                                 const ClearanceRule& rule, const Vec3& start, const Vec3& goal,
                                 const PlannerOptions& options, bool* is_local, WorkCounts* work) {
  std::vector<Vec3> out;
  *is_local = false;
  if (bounds.isEmpty()) return out;
  std::int64_t checks = 0;
  const auto is_valid = [&](const Vec3& p) {
    ++checks;
    if (!bounds.contains(p)) return false;
    const double required = rule.RequiredAt(p);
    return map.IsClear(p, required);
  };
  const double res = map.resolution();
  const auto add = [&](const Vec3& p) {
    for (const Vec3& o : out) {
      if ((o - p).norm() < res) return;
    }
    if (static_cast<int>(out.size()) < options.max_goal_candidates) out.push_back(p);
  };

  if (bounds.contains(goal) && is_valid(goal)) {
    out.push_back(goal);
  } else {
    *is_local = true;
    const Vec3 s = start.cwiseMax(bounds.min()).cwiseMin(bounds.max());
    // Where the way to the goal leaves the planning volume (the goal itself if inside).
    const Vec3 exit = bounds.contains(goal) ? goal : Vec3(s + ExitParameter(s, goal, bounds) * (goal - s));
    if (is_valid(exit)) {
      add(exit);
    } else {
      // The valid cell nearest to the exit point, within the search radius.
      const double r = options.local_goal_search_radius;
      const Eigen::AlignedBox3d box = map.Box();
      const Eigen::Vector3i dims =
          ((box.max() - box.min()) / res).array().round().cast<int>().matrix();
      const auto cell_of = [&](const Vec3& p) -> Eigen::Vector3i {
        return ((p - box.min()) / res).array().floor().cast<int>().matrix();
      };
      const Eigen::Vector3i lo = cell_of(exit - Vec3::Constant(r)).cwiseMax(0);
      const Eigen::Vector3i hi = cell_of(exit + Vec3::Constant(r)).cwiseMin(dims - Eigen::Vector3i::Ones());
      double best = std::numeric_limits<double>::infinity();
      Vec3 best_p = exit;
      for (int z = lo.z(); z <= hi.z(); ++z) {
        for (int y = lo.y(); y <= hi.y(); ++y) {
          for (int x = lo.x(); x <= hi.x(); ++x) {
            const Vec3 p = box.min() + (Eigen::Vector3d(x, y, z).array() + 0.5).matrix() * res;
            const double d = (p - exit).norm();
            if (d > r || d >= best || !bounds.contains(p)) continue;
            ++checks;
            const double required = rule.RequiredAt(p);
            if (map.IsClear(p, required)) {
              best = d;
              best_p = p;
            }
          }
        }
      }
      if (best < std::numeric_limits<double>::infinity()) add(best_p);
    }
    // Last resort, reachable by a straight line: the last free point from the start towards the
    // exit, if it makes real progress.
    const double step = res;
    const int n = static_cast<int>(std::floor((exit - s).norm() / step));
    Vec3 last = s;
    for (int i = 1; i <= n; ++i) {
      const Vec3 p = s + (exit - s) * (static_cast<double>(i) / n);
      if (!is_valid(p)) break;
      last = p;
    }
    if ((last - s).norm() >= std::max(1.0, 2.0 * step)) add(last);
  }
  if (work != nullptr) work->Add(WorkUnit::kStateCheck, checks);
  return out;
}

}  // namespace enavi::navstack
