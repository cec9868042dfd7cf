#include "navstack/perception/occupancy_map.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "tests/unit/perception/synthetic_depth.h"

namespace enavi::navstack {
namespace {

using testing::BoxAt;
using testing::CameraPose;
using testing::RenderFrame;
using testing::Scene;

const CameraIntrinsics kCam = CameraIntrinsics::Default();

// Side view (x forward, z up). The camera at the origin looks along +x at a 3 x 2 m wall whose
// face is at x = 3.05 (the middle of a 0.1 m cell); rays past its edges return nothing.
//
//        z
//        |          +--+
//   cam  o--------> |  |  wall x = [3.05, 3.45], y = [-1.5, 1.5], z = [-1, 1]
//        |          +--+
//                      ^ unknown behind
Scene Wall() { return Scene{{BoxAt({3.25, 0, 0}, {0.4, 3, 2})}, {}}; }

DepthFrame WallFrame(const Eigen::Vector3d& p_WC = Eigen::Vector3d::Zero(), double yaw = 0.0) {
  return RenderFrame(Wall(), kCam, CameraPose(p_WC, yaw));
}

std::string Name(CellState s) {
  return s == CellState::kOccupied ? "occupied" : s == CellState::kFree ? "free" : "unknown";
}

TEST(OccupancyMapTest, WallFrameMarksWallOccupiedFrontFreeBehindUnknown) {
  OccupancyMap map;
  map.Insert(WallFrame(), kCam, {});
  // The face x = 3.05 lies in the cells [3.0, 3.1).
  EXPECT_EQ(Name(map.Query({3.05, 0.0, 0.0})), "occupied");
  EXPECT_EQ(Name(map.Query({3.05, 1.2, -0.7})), "occupied");
  EXPECT_EQ(Name(map.Query({3.15, 0.0, 0.0})), "unknown") << "inside the wall, never seen";
  EXPECT_EQ(Name(map.Query({1.5, 0.0, 0.0})), "free");
  EXPECT_EQ(Name(map.Query({2.9, -1.0, 0.5})), "free");
  EXPECT_EQ(Name(map.Query({3.9, 0.0, 0.0})), "unknown") << "hidden behind the wall";
  EXPECT_EQ(Name(map.Query({-1.0, 0.0, 0.0})), "unknown") << "behind the camera";
  // Beside the wall nothing returned: no-return rays clear space up to max_range (5 m).
  EXPECT_EQ(Name(map.Query({4.0, 2.5, 0.0})), "free");

  // Nearly every cell of the wall face (x cell [3.0, 3.1)) is occupied.
  int occupied = 0, total = 0;
  for (double y = -1.45; y < 1.5; y += 0.1) {
    for (double z = -0.95; z < 1.0; z += 0.1) {
      ++total;
      occupied += map.Query({3.05, y, z}) == CellState::kOccupied ? 1 : 0;
    }
  }
  EXPECT_GE(occupied, total * 95 / 100) << occupied << " of " << total;
}

TEST(OccupancyMapTest, TwoPhaseEqualsSinglePhase) {
  const DepthFrame f1 = WallFrame({0, 0, 0});
  const DepthFrame f2 = WallFrame({0.5, 0.3, 0.2}, 0.1);
  OccupancyMap single, two_phase;
  single.Insert(f1, kCam, {});
  single.Insert(f2, kCam, {});

  // Both updates are computed before either is applied, as when two perception jobs overlap.
  WorkCounts work;
  const MapUpdate u1 = two_phase.ComputeUpdate(f1, kCam, {}, &work);
  const MapUpdate u2 = two_phase.ComputeUpdate(f2, kCam, {}, &work);
  EXPECT_EQ(two_phase.num_leaves(), 0u) << "ComputeUpdate must not touch the map";
  EXPECT_FALSE(two_phase.Apply(u1, &work).recomputed);
  EXPECT_FALSE(two_phase.Apply(u2, &work).recomputed);

  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -3, -2), Eigen::Vector3d(5, 3, 2));
  EXPECT_EQ(single.ExtractGrid(box).cells, two_phase.ExtractGrid(box).cells);
}

TEST(OccupancyMapTest, MatchesOctomapInsertPointCloud) {
  // Our ray casting (own DDA, deduplicated like computeUpdate) against OctoMap's own insertion
  // of the same points. Endpoint discretisation and no-return clearing are OctoMap-less
  // extensions, so they are off here.
  MapOptions o;
  o.discretize_endpoints = false;
  o.clear_no_return = false;
  o.local_half_extent = {50, 50, 50};
  OccupancyMap ours(o);
  octomap::OcTree reference(o.resolution);
  reference.setProbHit(o.prob_hit);
  reference.setProbMiss(o.prob_miss);
  reference.setClampingThresMin(o.clamp_min);
  reference.setClampingThresMax(o.clamp_max);
  reference.setOccupancyThres(o.occupancy_threshold);
  for (const DepthFrame& f : {WallFrame({0, 0, 0}), WallFrame({0.4, -0.2, 0.1}, -0.15)}) {
    const ScanPoints scan = BackProject(f, kCam, {});
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3f& p : scan.hits_W) cloud.push_back(p.x(), p.y(), p.z());
    const octomap::point3d origin(scan.origin_W.x(), scan.origin_W.y(), scan.origin_W.z());
    reference.insertPointCloud(cloud, origin, -1.0, false, false);
    ours.Insert(f, kCam, {});
  }
  const VoxelGrid grid = ours.ExtractGrid({Eigen::Vector3d(-1, -3, -2), Eigen::Vector3d(5, 3, 2)});
  int same = 0, known = 0;
  for (int z = 0; z < grid.dims.z(); ++z) {
    for (int y = 0; y < grid.dims.y(); ++y) {
      for (int x = 0; x < grid.dims.x(); ++x) {
        const Eigen::Vector3i c(x, y, z);
        const Eigen::Vector3d p = grid.CenterOf(c);
        const octomap::OcTreeNode* n = reference.search(p.x(), p.y(), p.z());
        const CellState theirs = n == nullptr                   ? CellState::kUnknown
                                 : reference.isNodeOccupied(n) ? CellState::kOccupied
                                                               : CellState::kFree;
        const CellState mine = grid.cells[grid.Index(c)];
        if (mine != CellState::kUnknown || theirs != CellState::kUnknown) {
          ++known;
          same += mine == theirs ? 1 : 0;
        }
      }
    }
  }
  ASSERT_GT(known, 5000);
  // Ties in the voxel walk could be broken differently on a handful of cells (none are today).
  EXPECT_GE(same, known * 995 / 1000) << same << " of " << known << " cells agree";
}

TEST(OccupancyMapTest, SetResolutionRebuildKeepsTheWall) {
  OccupancyMap map;
  for (int i = 0; i < 3; ++i) map.Insert(WallFrame({0.1 * i, 0, 0}), kCam, {});
  EXPECT_EQ(map.history_size(), 3);
  WorkCounts work;
  map.SetResolution(0.2, &work);
  EXPECT_DOUBLE_EQ(map.resolution(), 0.2);
  EXPECT_GT(work.Get(WorkUnit::kRayStep), 0) << "a rebuild is not free";
  EXPECT_GT(work.Get(WorkUnit::kRebuildVoxel), 0);
  EXPECT_EQ(Name(map.Query({3.1, 0.0, 0.0})), "occupied");
  EXPECT_EQ(Name(map.Query({1.5, 0.0, 0.0})), "free");
  EXPECT_EQ(Name(map.Query({4.1, 0.0, 0.0})), "unknown");
  const VoxelGrid grid = map.ExtractGrid({Eigen::Vector3d(0, -1, -1), Eigen::Vector3d(4, 1, 1)});
  EXPECT_DOUBLE_EQ(grid.resolution, 0.2);

  // Same resolution again: nothing to do.
  WorkCounts none;
  map.SetResolution(0.2, &none);
  EXPECT_EQ(none.Get(WorkUnit::kRayStep), 0);
  EXPECT_THROW(map.SetResolution(0.0), std::invalid_argument);
}

TEST(OccupancyMapTest, RebuiltLeavesTheOriginalUntouched) {
  OccupancyMap map;
  for (int i = 0; i < 3; ++i) map.Insert(WallFrame({0.1 * i, 0, 0}), kCam, {});
  const std::size_t leaves = map.num_leaves();
  WorkCounts work;
  const std::shared_ptr<OccupancyMap> coarse = map.Rebuilt(0.2, &work);
  EXPECT_DOUBLE_EQ(map.resolution(), 0.1);
  EXPECT_EQ(map.num_leaves(), leaves);
  EXPECT_DOUBLE_EQ(coarse->resolution(), 0.2);
  EXPECT_EQ(coarse->history_size(), 3);
  EXPECT_GT(work.Get(WorkUnit::kRayStep), 0);
  EXPECT_EQ(Name(coarse->Query({3.1, 0.0, 0.0})), "occupied");
  map.SetResolution(0.2);
  EXPECT_EQ(map.num_leaves(), coarse->num_leaves()) << "SetResolution is the same rebuild in place";
}

TEST(OccupancyMapTest, RebuildKeepsObstaclesOutOfViewAndDropsOldFreeSpace) {
  MapOptions o;
  o.rebuild_frames = 1;
  OccupancyMap map(o);
  map.Insert(WallFrame(), kCam, {});
  // The last frame sees nothing (the camera turned around). The wall, now behind the camera, must
  // survive the rebuild (the planner would fly into it otherwise); the free space in front of it
  // came only from the dropped frame.
  map.Insert(RenderFrame(Wall(), kCam, CameraPose({0, 0, 0}, M_PI)), kCam, {});
  EXPECT_EQ(map.history_size(), 1);
  EXPECT_EQ(Name(map.Query({3.05, 0, 0})), "occupied");
  EXPECT_EQ(Name(map.Query({1.5, 0, 0})), "free");
  WorkCounts work;
  map.SetResolution(0.2, &work);
  EXPECT_EQ(Name(map.Query({3.05, 0, 0})), "occupied");
  EXPECT_EQ(Name(map.Query({3.05, 1.0, 0.5})), "occupied");
  EXPECT_EQ(Name(map.Query({1.5, 0, 0})), "unknown");
  EXPECT_EQ(Name(map.Query({-3.1, 0, 0})), "free");
  EXPECT_GT(work.Get(WorkUnit::kRebuildVoxel), 0) << "carrying cells over and replaying frames is billed";
  EXPECT_EQ(work.Get(WorkUnit::kVoxelUpdate), 0) << "a fresh tree's writes are rebuild voxels, not leaf updates";
  EXPECT_GT(work.Get(WorkUnit::kRay), 0) << "the replayed frame's rays are cast again";

  // Back to the finer grid: every fine cell inside a carried coarse cell is occupied (conservative).
  map.SetResolution(0.1);
  EXPECT_EQ(Name(map.Query({3.05, 0, 0})), "occupied");
  EXPECT_EQ(Name(map.Query({3.15, 0, 0})), "occupied");
}

TEST(OccupancyMapTest, RebuildDropsObstaclesOutsideTheLocalBox) {
  MapOptions o;
  o.rebuild_frames = 1;
  o.local_half_extent = {8.0, 8.0, 4.0};
  OccupancyMap map(o);
  map.Insert(WallFrame(), kCam, {});
  // The newest frame is 20 m away, looking away from the wall: the wall is out of the local box.
  map.Insert(RenderFrame(Wall(), kCam, CameraPose({-20, 0, 0}, M_PI)), kCam, {});
  map.SetResolution(0.2);
  EXPECT_EQ(Name(map.Query({3.05, 0, 0})), "unknown");
}

TEST(OccupancyMapTest, ARebuildWithACarryRadiusForgetsWhatItCannotSeeAgain) {
  // The wall (3.05-3.45 m ahead) was seen, then the camera turned away: no kept frame shows it.
  // A rebuild carrying only cells within 2 m of the camera forgets it (unknown); one within 4 m
  // keeps it. The resolution may stay the same: this is the stack's map reset, not a switch.
  MapOptions o;
  o.rebuild_frames = 1;
  OccupancyMap map(o);
  map.Insert(WallFrame(), kCam, {});
  map.Insert(RenderFrame(Wall(), kCam, CameraPose({0, 0, 0}, M_PI)), kCam, {});
  ASSERT_EQ(Name(map.Query({3.05, 0, 0})), "occupied");
  WorkCounts near_work, far_work;
  const std::shared_ptr<OccupancyMap> near = map.Rebuilt(0.1, &near_work, 2.0);
  const std::shared_ptr<OccupancyMap> far = map.Rebuilt(0.1, &far_work, 4.0);
  EXPECT_EQ(Name(near->Query({3.05, 0, 0})), "unknown");
  EXPECT_EQ(Name(far->Query({3.05, 0, 0})), "occupied");
  EXPECT_EQ(Name(near->Query({-3.1, 0, 0})), "free") << "what the kept frame sees stays";
  EXPECT_LT(near_work.Get(WorkUnit::kRebuildVoxel), far_work.Get(WorkUnit::kRebuildVoxel)) << "fewer cells carried";
  EXPECT_DOUBLE_EQ(near->resolution(), 0.1);
  EXPECT_EQ(Name(map.Query({3.05, 0, 0})), "occupied") << "the original is untouched";
}

TEST(OccupancyMapTest, ExtractGridMatchesQueryCellByCell) {
  OccupancyMap map;
  // Repeated frames drive free cells to the clamp, so OctoMap prunes them into big leaves that
  // ExtractGrid must fill block-wise.
  for (int i = 0; i < 6; ++i) map.Insert(WallFrame({0.05 * i, 0.02 * i, 0}), kCam, {});
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.53, -2.07, -1.21), Eigen::Vector3d(5.02, 2.0, 1.2));
  WorkCounts work;
  const VoxelGrid grid = map.ExtractGrid(box, &work);
  EXPECT_EQ(work.Get(WorkUnit::kGridCell), grid.dims.prod());
  // Cells are aligned to the octree: the origin is a multiple of the resolution.
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(grid.origin[a] / 0.1, std::round(grid.origin[a] / 0.1), 1e-9);
    EXPECT_LE(grid.origin[a], box.min()[a]);
    EXPECT_GE(grid.origin[a] + grid.dims[a] * 0.1, box.max()[a] - 1e-9);
  }
  int counts[3] = {0, 0, 0};
  for (int z = 0; z < grid.dims.z(); ++z) {
    for (int y = 0; y < grid.dims.y(); ++y) {
      for (int x = 0; x < grid.dims.x(); ++x) {
        const Eigen::Vector3i c(x, y, z);
        const CellState s = grid.cells[grid.Index(c)];
        ++counts[static_cast<int>(s)];
        ASSERT_EQ(Name(s), Name(map.Query(grid.CenterOf(c)))) << "cell " << c.transpose();
      }
    }
  }
  EXPECT_GT(counts[0], 0);
  EXPECT_GT(counts[1], 0);
  EXPECT_GT(counts[2], 0);
  const OccupancyStats all = map.Stats({Eigen::Vector3d(-1, -6, -4), Eigen::Vector3d(6, 6, 4)});
  EXPECT_LT(map.num_leaves(), static_cast<std::size_t>(all.free + all.occupied))
      << "expected pruned leaves covering several cells";

  // Stats over the same box agree with the grid.
  const OccupancyStats stats = map.Stats(box);
  EXPECT_EQ(stats.unknown, counts[0]);
  EXPECT_EQ(stats.free, counts[1]);
  EXPECT_EQ(stats.occupied, counts[2]);
  EXPECT_EQ(stats.total, grid.dims.prod());
  EXPECT_THROW(map.ExtractGrid(Eigen::AlignedBox3d()), std::invalid_argument) << "empty box";
}

TEST(OccupancyMapTest, BoxEndingOnACellFaceDoesNotGrowTheGrid) {
  OccupancyMap map;
  const VoxelGrid grid = map.ExtractGrid({Eigen::Vector3d(-6, -6, 0), Eigen::Vector3d(6, 6, 4)});
  EXPECT_EQ(grid.dims, Eigen::Vector3i(120, 120, 40));
}

TEST(OccupancyMapTest, UpdateAtAnotherResolutionIsRecomputed) {
  OccupancyMap map;
  const MapUpdate stale = map.ComputeUpdate(WallFrame(), kCam, {});
  map.SetResolution(0.2);
  WorkCounts work;
  const ApplyResult r = map.Apply(stale, &work);
  EXPECT_TRUE(r.recomputed);
  EXPECT_GT(work.Get(WorkUnit::kRayStep), 0) << "recomputing is counted";

  MapOptions coarse;
  coarse.resolution = 0.2;
  OccupancyMap direct(coarse);
  direct.Insert(WallFrame(), kCam, {});
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -3, -2), Eigen::Vector3d(5, 3, 2));
  EXPECT_EQ(map.ExtractGrid(box).cells, direct.ExtractGrid(box).cells);

  MapUpdate pointless;  // no points to recompute from
  pointless.resolution = 0.1;
  EXPECT_THROW(map.Apply(pointless), std::logic_error);
}

TEST(OccupancyMapTest, WorkCountsScaleWithStride) {
  MapOptions o;
  o.discretize_endpoints = false;  // one ray per sample
  OccupancyMap map(o);
  const DepthFrame f = WallFrame();
  WorkCounts fine, coarse;
  PerceptionOptions p2, p4;
  p2.stride = 2;
  p4.stride = 4;
  map.Apply(map.ComputeUpdate(f, kCam, p2, &fine), &fine);
  map.Apply(map.ComputeUpdate(f, kCam, p4, &coarse), &coarse);
  EXPECT_EQ(fine.Get(WorkUnit::kBackProjection), 4 * coarse.Get(WorkUnit::kBackProjection));
  const double ratio = static_cast<double>(fine.Get(WorkUnit::kRayStep)) /
                       static_cast<double>(coarse.Get(WorkUnit::kRayStep));
  EXPECT_NEAR(ratio, 4.0, 0.3) << "four times the rays, same lengths";
  EXPECT_EQ(fine.Get(WorkUnit::kRay), 4 * coarse.Get(WorkUnit::kRay)) << "one ray per sampled pixel";
  EXPECT_GT(coarse.Get(WorkUnit::kVoxelUpdate), 0);
  EXPECT_GT(fine.Get(WorkUnit::kVoxelUpdate), coarse.Get(WorkUnit::kVoxelUpdate));

  // With endpoint discretisation (the default) fewer rays are cast, still more for stride 2.
  OccupancyMap dmap;
  WorkCounts dfine, dcoarse;
  dmap.ComputeUpdate(f, kCam, p2, &dfine);
  dmap.ComputeUpdate(f, kCam, p4, &dcoarse);
  EXPECT_LT(dfine.Get(WorkUnit::kRayStep), fine.Get(WorkUnit::kRayStep));
  EXPECT_GT(dfine.Get(WorkUnit::kRayStep), dcoarse.Get(WorkUnit::kRayStep));
}

TEST(OccupancyMapTest, EgoPlannersRayBreakCutsRayStepsAndKeepsTheMap) {
  // Every pixel, as the baseline maps (skip_pixel 2 of the 640x480 sensor = stride 1 here).
  PerceptionOptions every;
  every.stride = 1;
  const DepthFrame f = WallFrame();
  OccupancyMap full;
  MapOptions o;
  o.stop_at_traversed = true;
  OccupancyMap cut(o);
  WorkCounts w_full, w_cut;
  const MapUpdate u_full = full.ComputeUpdate(f, kCam, every, &w_full);
  const MapUpdate u_cut = cut.ComputeUpdate(f, kCam, every, &w_cut);
  EXPECT_EQ(u_cut.occupied_keys.size(), u_full.occupied_keys.size()) << "every end voxel is kept";
  EXPECT_LT(5 * w_cut.Get(WorkUnit::kRayStep), w_full.Get(WorkUnit::kRayStep))
      << "rays converge at the sensor: most stop a few voxels from their end";
  // The break leaves about a third of the full cast's free voxels cleared (0.33 on this frame):
  // the others stay unknown, which the planners read as free, as Ego-Planner's does.
  const double free_ratio = static_cast<double>(u_cut.free_keys.size()) / static_cast<double>(u_full.free_keys.size());
  EXPECT_GT(free_ratio, 0.25);
  EXPECT_LT(free_ratio, 0.5);
  cut.Apply(u_cut);
  EXPECT_EQ(Name(cut.Query({3.05, 0.0, 0.0})), "occupied");
  EXPECT_EQ(Name(cut.Query({1.5, 0.0, 0.0})), "free");
  EXPECT_EQ(Name(cut.Query({2.9, -1.0, 0.5})), "free");
  EXPECT_EQ(Name(cut.Query({3.9, 0.0, 0.0})), "unknown") << "hidden behind the wall";
}

TEST(OccupancyMapTest, DenseMarksAndHashSetsGiveTheSameUpdate) {
  // A frame's keys are deduplicated in a dense array over the local box when it is small enough
  // (6 m: 123^3 cells) and in hash sets otherwise (50 m); every ray here stays within 5 m, so
  // both must give the same keys in the same order.
  PerceptionOptions every;
  every.stride = 1;
  for (const bool stop : {false, true}) {
    MapOptions small, large;
    small.local_half_extent = {6, 6, 6};
    large.local_half_extent = {50, 50, 50};
    small.stop_at_traversed = large.stop_at_traversed = stop;
    const OccupancyMap dense_marks(small), hash_sets(large);
    for (const DepthFrame& f : {WallFrame(), WallFrame({0.4, -0.2, 0.1}, -0.15)}) {
      const MapUpdate a = dense_marks.ComputeUpdate(f, kCam, every);
      const MapUpdate b = hash_sets.ComputeUpdate(f, kCam, every);
      ASSERT_GT(a.free_keys.size(), 1000u);
      EXPECT_EQ(a.free_keys, b.free_keys) << "stop_at_traversed " << stop;
      EXPECT_EQ(a.occupied_keys, b.occupied_keys) << "stop_at_traversed " << stop;
      EXPECT_EQ(a.ray_steps, b.ray_steps) << "stop_at_traversed " << stop;
    }
  }
}

TEST(OccupancyMapTest, BlockStoreHoldsTheSameCellsAsTheOctree) {
  // The same frames into OctoMap's octree and into dense blocks: OctoMap's log-odds rule on the
  // same floats, so every cell state agrees, also after a rebuild at another resolution. Narrow
  // clamping bounds make the clamp decide cells: after three misses one hit marks a cell occupied
  // only if the misses were clamped, and after hits one miss frees it only if the hits were.
  MapOptions o;
  o.clamp_min = 0.45;
  o.clamp_max = 0.55;
  MapOptions b = o;
  b.storage = MapStorage::kBlocks;
  OccupancyMap octree(o), blocks(b);
  const DepthFrame nothing = RenderFrame(Scene{}, kCam, CameraPose({0, 0, 0}));
  for (const DepthFrame& f : {nothing, nothing, nothing, WallFrame(), WallFrame({0.4, -0.2, 0.1}, -0.15),
                              WallFrame(), WallFrame(), RenderFrame(Scene{}, kCam, CameraPose({0.2, 0.1, 0}, 0.1)),
                              WallFrame({1.0, 0.6, -0.3}, 0.3)}) {
    WorkCounts wo, wb;
    octree.Insert(f, kCam, {}, &wo);
    blocks.Insert(f, kCam, {}, &wb);
    EXPECT_EQ(wo.n, wb.n) << "the same work";
  }
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -4, -3), Eigen::Vector3d(6, 4, 3));
  const VoxelGrid g = octree.ExtractGrid(box);
  ASSERT_EQ(g.cells, blocks.ExtractGrid(box).cells);
  const OccupancyStats so = octree.Stats(box), sb = blocks.Stats(box);
  EXPECT_GT(so.occupied, 200);
  EXPECT_GT(so.free, 5000);
  EXPECT_EQ(so.occupied, sb.occupied);
  EXPECT_EQ(so.free, sb.free);
  EXPECT_EQ(so.unknown, sb.unknown);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(3.05, 0, 0), Eigen::Vector3d(1.5, 0, 0),
                                  Eigen::Vector3d(3.9, 0, 0), Eigen::Vector3d(-200, 0, 0)}) {
    EXPECT_EQ(Name(octree.Query(p)), Name(blocks.Query(p))) << p.transpose();
  }
  // A sub-box whose faces cut through blocks.
  const Eigen::AlignedBox3d part(Eigen::Vector3d(2.33, -0.77, -0.41), Eigen::Vector3d(3.51, 1.29, 0.66));
  EXPECT_EQ(octree.ExtractGrid(part).cells, blocks.ExtractGrid(part).cells);

  octree.SetResolution(0.2);
  blocks.SetResolution(0.2);
  EXPECT_EQ(octree.ExtractGrid(box).cells, blocks.ExtractGrid(box).cells) << "after a rebuild";
  blocks.Clear();
  const VoxelGrid cleared = blocks.ExtractGrid(box);
  EXPECT_TRUE(std::all_of(cleared.cells.begin(), cleared.cells.end(),
                          [](CellState c) { return c == CellState::kUnknown; }));
  EXPECT_EQ(blocks.num_leaves(), 0u);
}

TEST(OccupancyMapTest, LocalBoxLimitsTheUpdate) {
  MapOptions o;
  o.local_half_extent = {2.0, 2.0, 2.0};
  OccupancyMap map(o);
  map.Insert(WallFrame(), kCam, {});
  EXPECT_EQ(Name(map.Query({1.5, 0, 0})), "free");
  EXPECT_EQ(Name(map.Query({2.5, 0, 0})), "unknown") << "outside the local box";
  EXPECT_EQ(Name(map.Query({3.1, 0, 0})), "unknown") << "the wall is outside the local box";
}

TEST(OccupancyMapTest, NoReturnClearingIsAnOption) {
  const DepthFrame nothing = RenderFrame(Scene{}, kCam, CameraPose({0, 0, 0}));
  OccupancyMap clearing;
  clearing.Insert(nothing, kCam, {});
  EXPECT_EQ(Name(clearing.Query({4.0, 0, 0})), "free");
  EXPECT_EQ(Name(clearing.Query({5.5, 0, 0})), "unknown") << "beyond max_range";
  MapOptions o;
  o.clear_no_return = false;
  OccupancyMap keeping(o);
  keeping.Insert(nothing, kCam, {});
  EXPECT_EQ(Name(keeping.Query({4.0, 0, 0})), "unknown");
}

TEST(OccupancyMapTest, RejectsBadOptions) {
  MapOptions o;
  o.resolution = 0.0;
  try {
    OccupancyMap map(o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("MapOptions.resolution"), std::string::npos) << e.what();
  }
  o = {};
  o.prob_hit = 0.4;
  EXPECT_THROW(OccupancyMap{o}, std::invalid_argument);
  o = {};
  o.clamp_max = 0.3;
  EXPECT_THROW(OccupancyMap{o}, std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
