#include "workers/sim/moving_scene.h"

#include <stdexcept>
#include <string>

#include "workers/sim/embree_impl.h"
#include "workers/sim/mesh_check.h"

namespace enavi::sim {

MovingScene::Impl::~Impl() {
  for (RTCGeometry g : geometries) rtcReleaseGeometry(g);
  if (movers) rtcReleaseScene(movers);
}

MovingScene::MovingScene(std::shared_ptr<const EmbreeScene> world, const std::vector<worlds::TriangleMesh>& mover_meshes,
                         const EmbreeDevice& embree_device)
    : impl_(std::make_unique<Impl>()) {
  if (!world) throw std::invalid_argument("MovingScene: world scene is null");
  Impl& s = *impl_;
  RTCDevice device = embree_device.impl().device;
  s.device = device;
  s.world = std::move(world);
  s.movers = rtcNewScene(device);
  ThrowIfEmbreeError(device, "rtcNewScene");
  // Rebuilt every frame: fast builds; robust as the world's scene (no seams seen through).
  rtcSetSceneFlags(s.movers, RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(s.movers, RTC_BUILD_QUALITY_LOW);

  // Geometry i: mover i's triangles, in Embree's own buffers (rewritten per frame).
  s.local = mover_meshes;
  s.mover_planes.resize(mover_meshes.size());
  for (std::size_t i = 0; i < mover_meshes.size(); ++i) {
    const worlds::TriangleMesh& mesh = mover_meshes[i];
    CheckTriangleMesh(mesh, "MovingScene");
    if (mesh.triangles.empty()) throw std::invalid_argument("MovingScene: mover " + std::to_string(i) + " has no triangles");
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    ThrowIfEmbreeError(device, "rtcNewGeometry");
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_LOW);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.vertices.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), mesh.triangles.size()));
    if (vertices == nullptr || indices == nullptr) {
      rtcReleaseGeometry(g);
      ThrowIfEmbreeError(device, "rtcSetNewGeometryBuffer");
      throw std::runtime_error("Embree error in rtcSetNewGeometryBuffer: no buffer returned");
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) indices[3 * t + k] = static_cast<unsigned>(mesh.triangles[t][k]);
    }
    s.geometries.push_back(g);
    rtcAttachGeometryByID(s.movers, g, static_cast<unsigned>(i));
    ThrowIfEmbreeError(device, "rtcAttachGeometryByID");
  }
  for (const auto& p : s.mover_planes) s.planes.push_back(&p);
  SetPoses(std::vector<Eigen::Isometry3d>(mover_meshes.size(), Eigen::Isometry3d::Identity()));
}

MovingScene::~MovingScene() = default;

std::size_t MovingScene::mover_count() const { return impl_->geometries.size(); }

void MovingScene::SetPoses(const std::vector<Eigen::Isometry3d>& X_WM) {
  Impl& s = *impl_;
  if (X_WM.size() != s.geometries.size()) {
    throw std::invalid_argument("MovingScene::SetPoses: " + std::to_string(X_WM.size()) + " poses for " +
                                std::to_string(s.geometries.size()) + " movers");
  }
  s.bounds_W.assign(X_WM.size(), Eigen::AlignedBox3d());
  for (std::size_t i = 0; i < X_WM.size(); ++i) {
    const worlds::TriangleMesh& mesh = s.local[i];
    auto* vertices = static_cast<float*>(rtcGetGeometryBufferData(s.geometries[i], RTC_BUFFER_TYPE_VERTEX, 0));
    // Placed in double, stored as float: the same floats give Embree its triangles and the
    // camera its planes (as for the world's scene).
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      const Eigen::Vector3d p = X_WM[i] * mesh.vertices[v].cast<double>();
      for (int k = 0; k < 3; ++k) vertices[3 * v + k] = static_cast<float>(p[k]);
      s.bounds_W[i].extend(p);
    }
    auto& planes = s.mover_planes[i];
    planes.clear();
    for (const auto& tri : mesh.triangles) {
      Eigen::Vector3d c[3];
      for (int k = 0; k < 3; ++k) {
        const float* f = vertices + 3 * tri[k];
        c[k] = Eigen::Vector3d(f[0], f[1], f[2]);
      }
      const Eigen::Vector3d n = (c[1] - c[0]).cross(c[2] - c[0]);
      planes.emplace_back(n.x(), n.y(), n.z(), n.dot(c[0]));
    }
    rtcUpdateGeometryBuffer(s.geometries[i], RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(s.geometries[i]);
  }
  rtcCommitScene(s.movers);
  ThrowIfEmbreeError(s.device, "rtcCommitScene");
}

}  // namespace enavi::sim
