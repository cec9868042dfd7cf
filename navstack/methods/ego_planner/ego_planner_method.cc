#include "navstack/methods/ego_planner/ego_planner_method.h"

#include <iterator>

#include "navstack/methods/ego_planner/ego_planner_node.h"

namespace enavi::navstack {

MethodInfo EgoPlannerMethod() {
  const EgoPlannerOptions d;
  MethodInfo m;
  m.name = "baseline";
  m.summary = "the paper's baseline: Ego-Planner's node (one ROS callback queue, distance-triggered replans, "
              "safety check with emergency stop) at 30 Hz / 20 Hz / 0.1 m";
  // ego_planner_node.cpp: ros::spin(), one thread, callbacks in arrival order.
  m.scheduler = {SchedulingPolicy::kFifoNonPreemptive, 1};
  // Its map is dense arrays and its search a bit grid, not our octree and distance field: a voxel
  // update or a state check is other code at another price.
  m.cost_family = "ego_planner";
  // Calibration: each level of E-Navi's resolution ladder (ResolutionAdapterOptions) once, on the
  // scenarios in turn.
  const double ladder[] = {0.5, 0.4, 0.3, 0.2, 0.15, 0.1};
  const char* const scenarios[] = {"s1", "s2", "s3", "s4", "s5"};
  for (std::size_t i = 0; i < std::size(ladder); ++i)
    m.calibration.push_back({scenarios[i % 5], {{"map.resolution", ladder[i]}}});
  m.task_labels = {"occupancy update", "FSM (replans)", "safety check (and its replans)", "unused", "eci", "unused"};
  m.tunables = {
      {"map.resolution", 0.05, 1.0, 0.1, false, "grid_map/resolution, m"},
      {"ego.occupancy_hz", 1.0, 60.0, d.occupancy_hz, false, "occupancy timer, Hz (paper: 30; Ego-Planner: 20)"},
      {"ego.safety_hz", 1.0, 100.0, d.safety_hz, false, "safety-check timer, Hz"},
      {"ego.fsm_hz", 1.0, 500.0, d.fsm_hz, false, "FSM timer, Hz"},
      {"ego.skip_pixel", 1, 16, static_cast<double>(d.skip_pixel), true, "grid_map/skip_pixel, pixels of the 640x480 frame"},
      {"ego.thresh_replan", 0.1, 20.0, d.thresh_replan, false, "fsm/thresh_replan, m"},
      {"ego.thresh_no_replan", 0.0, 20.0, d.thresh_no_replan, false, "fsm/thresh_no_replan, m"},
      {"ego.planning_horizon", 1.0, 30.0, d.planning_horizon, false, "fsm/planning_horizon, m"},
      {"ego.emergency_time", 0.0, 10.0, d.emergency_time, false, "fsm/emergency_time, s"},
      {"ego.search_time_limit", 0.0, 10.0, d.search_time_limit, false, "path search limit, board s (0: none)"},
      {"ego.stamp_at_plan_end", 0, 1, 1, true, "1: trajectories stamped when planning ends (reference jumps back)"},
      {"ego.safety_replan_inline", 0, 1, 1, true, "1: the safety check replans at once inside its callback"},
      {"ego.emergency_stop", 0, 1, 1, true, "1: a failed safety replan with a hit < emergency_time ahead stops"},
      {"ego.check_two_thirds", 0, 1, 1, true, "1: the safety check samples only the first 2/3 of a trajectory"},
      {"ego.newest_frame_only", 0, 1, 1, true, "1: the occupancy update raycasts only the newest frame"},
      {"ego.ray_break", 0, 1, 1, true, "1: a ray stops at the first voxel this frame already cleared (grid_map raycast)"},
      {"ego.dense_map", 0, 1, 1, true, "1: log-odds in dense blocks as grid_map's arrays, 0: OctoMap's octree (same cells, slower)"},
  };
  m.configure = [](const MethodSetup&, MethodOptions* o) {
    // Ego-Planner's ESDF-free rebound optimisation (navstack/planning/README.md).
    o->planner.optimizer = PlannerOptimizer::kRebound;
  };
  m.make = [](const MethodOptions& o, TaskExecutor* executor, const VehicleState& initial) {
    EgoPlannerOptions e;
    // grid_map parameters of launch/advanced_param.xml.
    e.map.prob_hit = 0.65;
    e.map.prob_miss = 0.35;
    e.map.clamp_min = 0.12;
    e.map.clamp_max = 0.90;
    e.map.occupancy_threshold = 0.80;
    e.map.local_half_extent = Eigen::Vector3d(5.5, 5.5, 4.5);
    e.map.resolution = o.Param("map.resolution");
    e.map.stop_at_traversed = o.Param("ego.ray_break") > 0;
    // plan_env/src/grid_map.cpp keeps the log-odds in dense arrays (occupancy_buffer_). The
    // baseline never changes resolution, so the octree's cheap rebuilds buy it nothing.
    e.map.storage = o.Param("ego.dense_map") > 0 ? MapStorage::kBlocks : MapStorage::kOctree;
    e.perception.min_range = 0.2;  // depth_filter_mindist
    e.perception.max_range = 4.5;  // max_ray_length (depth_filter_maxdist 5.0 cuts further returns)
    if (o.perception_stride) e.perception.stride = *o.perception_stride;
    if (o.perception_max_range) e.perception.max_range = *o.perception_max_range;
    e.occupancy_hz = o.Param("ego.occupancy_hz");
    e.safety_hz = o.Param("ego.safety_hz");
    e.fsm_hz = o.Param("ego.fsm_hz");
    e.skip_pixel = static_cast<int>(o.Param("ego.skip_pixel"));
    e.thresh_replan = o.Param("ego.thresh_replan");
    e.thresh_no_replan = o.Param("ego.thresh_no_replan");
    e.planning_horizon = o.Param("ego.planning_horizon");
    e.emergency_time = o.Param("ego.emergency_time");
    e.search_time_limit = o.Param("ego.search_time_limit");
    e.stamp_at_plan_end = o.Param("ego.stamp_at_plan_end") > 0;
    e.safety_replan_inline = o.Param("ego.safety_replan_inline") > 0;
    e.emergency_stop = o.Param("ego.emergency_stop") > 0;
    e.check_two_thirds = o.Param("ego.check_two_thirds") > 0;
    e.newest_frame_only = o.Param("ego.newest_frame_only") > 0;
    return std::unique_ptr<Navigator>(std::make_unique<EgoPlannerNode>(o, e, executor, initial));
  };
  return m;
}

}  // namespace enavi::navstack
