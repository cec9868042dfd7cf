#include "server/bench/raycast_bench.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "navstack/common/cpu_time.h"
#include "workers/sim/bullet_raycaster.h"
#include "workers/sim/static_world.h"

namespace enavi::bench {
namespace {

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double MraysPerSecond(std::int64_t rays, double seconds) {
  return seconds > 0.0 ? static_cast<double>(rays) / seconds * 1e-6
                       : std::numeric_limits<double>::quiet_NaN();
}

// Camera poses along the line, at start height, looking along it.
std::vector<Eigen::Isometry3d> FramePoses(const Eigen::Vector3d& start,
                                          const Eigen::Vector3d& goal, int frames,
                                          const navstack::VehicleParams& vehicle) {
  const Eigen::Vector2d line = (goal - start).head<2>();
  if (!(line.norm() > 0.0)) {
    throw std::invalid_argument(
        "RunRaycastBench: start and goal must differ horizontally (camera looks along the line)");
  }
  const double yaw = std::atan2(line.y(), line.x());
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < frames; ++i) {
    const double s = frames > 1 ? static_cast<double>(i) / (frames - 1) : 0.0;
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = start + s * (goal - start);
    X_WB.translation().z() = start.z();
    X_WB.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    poses.push_back(sim::CameraPoseInWorld(X_WB, vehicle));
  }
  return poses;
}

}  // namespace

DepthComparison& DepthComparison::operator+=(const DepthComparison& o) {
  both_hit += o.both_hit;
  one_sided += o.one_sided;
  disagreeing += o.disagreeing;
  max_diff = std::max(max_diff, o.max_diff);
  max_diff_interior = std::max(max_diff_interior, o.max_diff_interior);
  return *this;
}

DepthComparison CompareDepthImages(const navstack::DepthImage& a, const navstack::DepthImage& b,
                                   double tolerance) {
  if (a.width != b.width || a.height != b.height ||
      a.data.size() != static_cast<std::size_t>(a.width) * a.height ||
      b.data.size() != a.data.size()) {
    throw std::invalid_argument("CompareDepthImages: images differ in size");
  }
  using navstack::DepthImage;
  // (u, v) lies on a locally planar surface of `a`: inverse depth is linear in pixel
  // coordinates on a plane, so its second difference along each line through the 3x3
  // neighbourhood is ~0; a silhouette or crease breaks that.
  auto interior = [&a](int u, int v) {
    if (u == 0 || v == 0 || u == a.width - 1 || v == a.height - 1) return false;
    const double inv = 1.0 / a.at(u, v);
    constexpr int kLines[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    for (const auto& l : kLines) {
      const float p = a.at(u + l[0], v + l[1]), q = a.at(u - l[0], v - l[1]);
      if (!DepthImage::Valid(p) || !DepthImage::Valid(q)) return false;
      if (std::abs(1.0 / p + 1.0 / q - 2.0 * inv) > 1e-3 * inv) return false;
    }
    return true;
  };
  DepthComparison c;
  for (int v = 0; v < a.height; ++v) {
    for (int u = 0; u < a.width; ++u) {
      const float da = a.at(u, v), db = b.at(u, v);
      const bool hit_a = DepthImage::Valid(da), hit_b = DepthImage::Valid(db);
      if (hit_a != hit_b) {
        ++c.one_sided;
        continue;
      }
      if (!hit_a) continue;
      ++c.both_hit;
      const double diff = std::abs(static_cast<double>(da) - static_cast<double>(db));
      if (diff > tolerance) ++c.disagreeing;
      c.max_diff = std::max(c.max_diff, diff);
      if (interior(u, v)) c.max_diff_interior = std::max(c.max_diff_interior, diff);
    }
  }
  return c;
}

RaycastBenchResult RunRaycastBench(const worlds::TriangleMesh& mesh, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& goal,
                                   const RaycastBenchOptions& options) {
  if (options.frames < 1) {
    throw std::invalid_argument("RaycastBenchOptions.frames: must be >= 1, got " +
                                std::to_string(options.frames));
  }
  if (options.bullet_frames < 0 || options.bullet_frames > options.frames) {
    throw std::invalid_argument("RaycastBenchOptions.bullet_frames: must be in [0, frames = " +
                                std::to_string(options.frames) + "], got " +
                                std::to_string(options.bullet_frames));
  }
  if (!start.allFinite() || !goal.allFinite()) {
    throw std::invalid_argument("RunRaycastBench: start and goal must be finite");
  }
  sim::CheckIntrinsics(options.intrinsics);
  const navstack::CameraIntrinsics& k = options.intrinsics;
  const std::vector<Eigen::Isometry3d> poses =
      FramePoses(start, goal, options.frames, options.vehicle);
  const std::int64_t pixels = static_cast<std::int64_t>(k.width) * k.height;

  RaycastBenchResult r;
  r.triangles = mesh.triangles.size();
  r.width = k.width;
  r.height = k.height;
  r.frames = options.frames;
  r.bullet_frames = options.bullet_frames;
  r.embree_mode = sim::ToString(options.mode);
  r.embree = sim::EmbreeDevice::Get().Info();

  double t0 = WallSeconds();
  const sim::EmbreeScene scene(mesh);
  r.embree_build_s = WallSeconds() - t0;
  t0 = WallSeconds();
  auto static_world = std::make_shared<const sim::StaticCollisionWorld>(mesh);
  r.bullet_build_s = WallSeconds() - t0;

  // Frames shared with Bullet: evenly spaced, first and last included.
  std::vector<int> shared;
  for (int j = 0; j < options.bullet_frames; ++j) {
    shared.push_back(options.bullet_frames > 1
                         ? static_cast<int>(std::lround(static_cast<double>(j) *
                                                        (options.frames - 1) /
                                                        (options.bullet_frames - 1)))
                         : 0);
  }

  // Embree: every frame in the headline mode (keeping the shared frames), then other modes.
  std::vector<navstack::DepthImage> embree_images(shared.size());
  std::vector<sim::EmbreeRayMode> modes{options.mode};
  modes.insert(modes.end(), options.compare_modes.begin(), options.compare_modes.end());
  std::int64_t valid = 0;
  navstack::DepthImage image;
  for (std::size_t m = 0; m < modes.size(); ++m) {
    const sim::DepthCamera camera(k, sim::DepthNoise{}, modes[m]);
    double cpu = 0.0;
    std::size_t next_shared = 0;
    for (int i = 0; i < options.frames; ++i) {
      const double c0 = navstack::ThreadCpuSeconds();
      camera.Render(scene, poses[i], &image);
      cpu += navstack::ThreadCpuSeconds() - c0;
      if (m != 0) continue;
      for (float d : image.data) valid += navstack::DepthImage::Valid(d) ? 1 : 0;
      while (next_shared < shared.size() && shared[next_shared] == i) {
        embree_images[next_shared++] = image;
      }
    }
    const std::int64_t rays = pixels * options.frames;
    r.modes.push_back({sim::ToString(modes[m]), cpu, MraysPerSecond(rays, cpu)});
  }
  r.embree_rays = pixels * options.frames;
  r.embree_cpu_s = r.modes.front().cpu_s;
  r.embree_mrays_per_s_per_core = r.modes.front().mrays_per_s_per_core;
  r.embree_valid_fraction = static_cast<double>(valid) / static_cast<double>(r.embree_rays);

  // Bullet on the shared frames, compared pixel by pixel.
  r.speedup_vs_bullet = std::numeric_limits<double>::quiet_NaN();
  r.bullet_mrays_per_s_per_core = std::numeric_limits<double>::quiet_NaN();
  if (!shared.empty()) {
    sim::BulletRayCaster bullet(static_world, k);
    double cpu = 0.0;
    DepthComparison agreement;
    for (std::size_t j = 0; j < shared.size(); ++j) {
      const double c0 = navstack::ThreadCpuSeconds();
      bullet.Render(poses[shared[j]], &image);
      cpu += navstack::ThreadCpuSeconds() - c0;
      agreement += CompareDepthImages(embree_images[j], image);
    }
    r.both_hit_pixels = agreement.both_hit;
    r.one_sided_pixels = agreement.one_sided;
    r.disagreeing_pixels = agreement.disagreeing;
    r.max_depth_disagreement_m = agreement.max_diff;
    r.max_depth_disagreement_interior_m = agreement.max_diff_interior;
    r.bullet_rays = pixels * static_cast<std::int64_t>(shared.size());
    r.bullet_cpu_s = cpu;
    r.bullet_mrays_per_s_per_core = MraysPerSecond(r.bullet_rays, cpu);
    r.speedup_vs_bullet = r.embree_mrays_per_s_per_core / r.bullet_mrays_per_s_per_core;
  }
  return r;
}

nlohmann::json ToJson(const RaycastBenchResult& r) {
  nlohmann::json modes = nlohmann::json::array();
  for (const RaycastModeTiming& m : r.modes) {
    modes.push_back(
        {{"mode", m.mode}, {"cpu_s", m.cpu_s}, {"mrays_per_s_per_core", m.mrays_per_s_per_core}});
  }
  return {
      {"triangles", r.triangles},
      {"width", r.width},
      {"height", r.height},
      {"frames", r.frames},
      {"bullet_frames", r.bullet_frames},
      {"embree_rays", r.embree_rays},
      {"bullet_rays", r.bullet_rays},
      {"embree_build_s", r.embree_build_s},
      {"bullet_build_s", r.bullet_build_s},
      {"embree_cpu_s", r.embree_cpu_s},
      {"bullet_cpu_s", r.bullet_cpu_s},
      {"embree_mrays_per_s_per_core", r.embree_mrays_per_s_per_core},
      {"bullet_mrays_per_s_per_core", r.bullet_mrays_per_s_per_core},
      {"speedup_vs_bullet", r.speedup_vs_bullet},
      {"max_depth_disagreement_m", r.max_depth_disagreement_m},
      {"max_depth_disagreement_interior_m", r.max_depth_disagreement_interior_m},
      {"both_hit_pixels", r.both_hit_pixels},
      {"disagreeing_pixels", r.disagreeing_pixels},
      {"one_sided_pixels", r.one_sided_pixels},
      {"embree_valid_fraction", r.embree_valid_fraction},
      {"embree_mode", r.embree_mode},
      {"embree",
       {{"version", r.embree.version},
        {"native_ray4", r.embree.native_ray4},
        {"native_ray8", r.embree.native_ray8},
        {"native_ray16", r.embree.native_ray16},
        {"ray_stream", r.embree.ray_stream},
        {"tasking", r.embree.tasking},
        {"ray_kernels", r.embree.ray_kernels}}},
      {"modes", modes},
  };
}

}  // namespace enavi::bench
