#include "workers/sim/depth_camera.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "workers/sim/camera_rays.h"
#include "workers/sim/embree_impl.h"
#include "workers/sim/moving_scene.h"

namespace enavi::sim {
namespace {

using navstack::CameraIntrinsics;
using navstack::DepthImage;

// Embree is slow on denormals; flush them to zero while rendering only, and restore the
// caller's floating-point mode afterwards so other code on this thread is unaffected.
class FlushDenormalsScope {
 public:
#if defined(__SSE__)
  FlushDenormalsScope() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }  // FTZ | DAZ
  ~FlushDenormalsScope() { _mm_setcsr(saved_); }

 private:
  unsigned saved_;
#endif
};

struct RenderSetup {
  RTCScene scene;
  /// Triangle planes by geometry: [0] the world's, or mover i's at this frame (MovingScene).
  const std::vector<const std::vector<Eigen::Vector4d>*>& planes;
  const PixelRays& rays;
  CameraRayFrame frame;
  int width, height;
  float min_range, max_range;
  float* depth;
  Eigen::Vector3d origin;  ///< frame.origin in double, for PixelDepth
};

// The pixel's depth from Embree's answer. Embree's own hit distance carries its kernels'
// approximate reciprocal, whose last bits depend on the CPU's vendor (embree_scene.h); the
// distance is recomputed here in double from the plane of the triangle Embree found, so only
// which triangle a ray hits comes from Embree.
float HitDistance(const RenderSetup& s, unsigned geom, unsigned prim, float dir_x, float dir_y, float dir_z,
                  float t_embree) {
  const Eigen::Vector4d& plane = (*s.planes[geom])[prim];
  const double along = plane.x() * dir_x + plane.y() * dir_y + plane.z() * dir_z;
  const double t = (plane.w() - plane.head<3>().dot(s.origin)) / along;
  // A ray Embree hit is not parallel to the triangle; keep its distance if it somehow was.
  return std::isfinite(t) ? static_cast<float>(t) : t_embree;
}

float PixelDepth(const RenderSetup& s, unsigned geom, unsigned prim, float dir_x, float dir_y, float dir_z,
                 float t_embree) {
  if (geom == RTC_INVALID_GEOMETRY_ID) return navstack::DepthImage::kNoReturn;
  return DepthOrNoReturn(true, HitDistance(s, geom, prim, dir_x, dir_y, dir_z, t_embree), s.min_range, s.max_range);
}

RTCIntersectContext CoherentContext() {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  return context;
}

void FillRay(const RenderSetup& s, int u, int v, RTCRay* ray) {
  const Eigen::Vector3f d = s.frame.Direction(s.rays.x_of_u[u], s.rays.y_of_v[v]);
  ray->org_x = s.frame.origin.x();
  ray->org_y = s.frame.origin.y();
  ray->org_z = s.frame.origin.z();
  ray->dir_x = d.x();
  ray->dir_y = d.y();
  ray->dir_z = d.z();
  // From the camera centre: a surface nearer than min_range must hide what is behind it.
  ray->tnear = 0.0f;
  ray->tfar = s.max_range;
  ray->time = 0.0f;
  ray->mask = 0xFFFFFFFFu;
  ray->id = 0;
  ray->flags = 0;
}

void RenderSingle(const RenderSetup& s) {
  RTCIntersectContext context = CoherentContext();
  RTCRayHit rh;
  for (int v = 0; v < s.height; ++v) {
    for (int u = 0; u < s.width; ++u) {
      FillRay(s, u, v, &rh.ray);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(s.scene, &context, &rh);
      s.depth[v * s.width + u] =
          PixelDepth(s, rh.hit.geomID, rh.hit.primID, rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z, rh.ray.tfar);
    }
  }
}

// Packets of N = TW x TH rays over pixel tiles; lanes outside the image are masked off.
template <int TW, int TH, typename RayHitN, typename IntersectN>
void RenderPackets(const RenderSetup& s, IntersectN intersect) {
  constexpr int N = TW * TH;
  RTCIntersectContext context = CoherentContext();
  alignas(64) RayHitN rh;
  alignas(64) int valid[N];
  // Embree writes only tfar and the hit fields: the rest is set once per frame.
  for (int j = 0; j < N; ++j) {
    rh.ray.org_x[j] = s.frame.origin.x();
    rh.ray.org_y[j] = s.frame.origin.y();
    rh.ray.org_z[j] = s.frame.origin.z();
    rh.ray.tnear[j] = 0.0f;
    rh.ray.time[j] = 0.0f;
    rh.ray.mask[j] = 0xFFFFFFFFu;
    rh.ray.id[j] = 0;
    rh.ray.flags[j] = 0;
  }
  // Ray tables padded to whole tiles, so a tile row is TW straight loads the compiler vectorises;
  // padded lanes are masked off and never traced.
  std::vector<float> xs(s.rays.x_of_u), ys(s.rays.y_of_v);
  xs.resize((s.width + TW - 1) / TW * TW, 0.0f);
  ys.resize((s.height + TH - 1) / TH * TH, 0.0f);
  const Eigen::Vector3f& ex = s.frame.ex;
  const Eigen::Vector3f& ey = s.frame.ey;
  const Eigen::Vector3f& ez = s.frame.ez;
  for (int v0 = 0; v0 < s.height; v0 += TH) {
    for (int u0 = 0; u0 < s.width; u0 += TW) {
      for (int dv = 0; dv < TH; ++dv) {
        const float y = ys[v0 + dv];
        const bool row_inside = v0 + dv < s.height;
        for (int du = 0; du < TW; ++du) {
          const int j = dv * TW + du;
          const float x = xs[u0 + du];
          valid[j] = row_inside && u0 + du < s.width ? -1 : 0;
          // CameraRayFrame::Direction, written out per component in the same operation order.
          rh.ray.dir_x[j] = (ex.x() * x + ey.x() * y) + ez.x();
          rh.ray.dir_y[j] = (ex.y() * x + ey.y() * y) + ez.y();
          rh.ray.dir_z[j] = (ex.z() * x + ey.z() * y) + ez.z();
          rh.ray.tfar[j] = s.max_range;
          rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        }
      }
      intersect(valid, s.scene, &context, &rh);
      for (int dv = 0; dv < TH && v0 + dv < s.height; ++dv) {
        float* row = s.depth + static_cast<std::size_t>(v0 + dv) * s.width + u0;
        for (int du = 0; du < TW && u0 + du < s.width; ++du) {
          const int j = dv * TW + du;
          row[du] = PixelDepth(s, rh.hit.geomID[j], rh.hit.primID[j], rh.ray.dir_x[j], rh.ray.dir_y[j],
                               rh.ray.dir_z[j], rh.ray.tfar[j]);
        }
      }
    }
  }
}

// Ray streams of up to 16x16 coherent rays; Embree forms its own packets from them.
void RenderStream(const RenderSetup& s) {
  constexpr int kTile = 16;
  RTCIntersectContext context = CoherentContext();
  std::vector<RTCRayHit> rh(kTile * kTile);
  for (int v0 = 0; v0 < s.height; v0 += kTile) {
    for (int u0 = 0; u0 < s.width; u0 += kTile) {
      const int tw = std::min(kTile, s.width - u0), th = std::min(kTile, s.height - v0);
      int m = 0;
      for (int dv = 0; dv < th; ++dv) {
        for (int du = 0; du < tw; ++du, ++m) {
          FillRay(s, u0 + du, v0 + dv, &rh[m].ray);
          rh[m].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        }
      }
      rtcIntersect1M(s.scene, &context, rh.data(), static_cast<unsigned>(m), sizeof(RTCRayHit));
      m = 0;
      for (int dv = 0; dv < th; ++dv) {
        for (int du = 0; du < tw; ++du, ++m) {
          const RTCRay& ray = rh[m].ray;
          s.depth[(v0 + dv) * s.width + u0 + du] =
              PixelDepth(s, rh[m].hit.geomID, rh[m].hit.primID, ray.dir_x, ray.dir_y, ray.dir_z, ray.tfar);
        }
      }
    }
  }
}

// Uniform double in (0, 1] from the top 53 bits of a raw 64-bit draw.
double UnitOpenClosed(std::uint64_t bits) {
  return static_cast<double>((bits >> 11) + 1) * 0x1.0p-53;
}

// One frame of `camera` traced in `scene`, whose triangles' planes are `planes` (RenderSetup),
// before the sensor's noise.
void Trace(const DepthCamera& camera, RTCScene scene, RTCDevice device,
           const std::vector<const std::vector<Eigen::Vector4d>*>& planes, const Eigen::Isometry3d& X_WC,
           DepthImage* out) {
  if (out == nullptr) throw std::invalid_argument("DepthCamera::Render: out is null");
  if (!X_WC.matrix().allFinite()) {
    throw std::invalid_argument("DepthCamera::Render: X_WC is not finite");
  }
  const CameraIntrinsics& k = camera.intrinsics();
  out->width = k.width;
  out->height = k.height;
  out->data.assign(static_cast<std::size_t>(k.width) * k.height, DepthImage::kNoReturn);

  // Ray directions per column/row are rebuilt per call (cheap next to tracing) so that the
  // camera holds no buffers and can render from several threads.
  const PixelRays rays(k);
  const CameraRayFrame frame(X_WC);
  const RenderSetup setup{scene,
                          planes,
                          rays,
                          frame,
                          k.width,
                          k.height,
                          static_cast<float>(k.min_range),
                          static_cast<float>(k.max_range),
                          out->data.data(),
                          frame.origin.cast<double>()};
  {
    FlushDenormalsScope flush;
    switch (camera.mode()) {
      case EmbreeRayMode::kSingle: RenderSingle(setup); break;
      case EmbreeRayMode::kPacket4: RenderPackets<2, 2, RTCRayHit4>(setup, &rtcIntersect4); break;
      case EmbreeRayMode::kPacket8: RenderPackets<4, 2, RTCRayHit8>(setup, &rtcIntersect8); break;
      case EmbreeRayMode::kPacket16:
        RenderPackets<4, 4, RTCRayHit16>(setup, &rtcIntersect16);
        break;
      case EmbreeRayMode::kStream: RenderStream(setup); break;
    }
  }
  ThrowIfEmbreeError(device, "rtcIntersect");
}

// The pixels whose rays can meet the box: the image of its part in front of the camera (its
// corners there and where its edges cross the plane just in front of the camera, projected,
// with a pixel of margin). Empty when it is out of view or beyond max_range (where a mover gives
// no return, as the sky does).
struct PixelRect {
  int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
};
PixelRect ImageOf(const Eigen::AlignedBox3d& box_W, const Eigen::Isometry3d& X_CW, const CameraIntrinsics& k) {
  constexpr double kNear = 1e-3;  // m: the plane the box is clipped at
  Eigen::Vector3d c[8];
  double z_min = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 8; ++i) {
    c[i] = X_CW * box_W.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
    z_min = std::min(z_min, c[i].z());
  }
  if (z_min > k.max_range) return {};
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min, v_min = u_min, v_max = -u_min;
  const auto add = [&](const Eigen::Vector3d& p) {
    const double u = k.fx * p.x() / p.z() + k.cx - 0.5, v = k.fy * p.y() / p.z() + k.cy - 0.5;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  };
  for (int i = 0; i < 8; ++i) {
    if (c[i].z() >= kNear) add(c[i]);
    for (int bit = 1; bit < 8; bit <<= 1) {  // the box's edges: corners one bit apart
      const int j = i | bit;
      if (j == i || (c[i].z() >= kNear) == (c[j].z() >= kNear)) continue;
      const double s = (kNear - c[i].z()) / (c[j].z() - c[i].z());
      add(c[i] + s * (c[j] - c[i]));
    }
  }
  if (!(u_min <= u_max)) return {};  // all behind the camera
  PixelRect r;
  r.u0 = static_cast<int>(std::max(0.0, std::floor(u_min) - 1));
  r.u1 = static_cast<int>(std::min(k.width - 1.0, std::ceil(u_max) + 1));
  r.v0 = static_cast<int>(std::max(0.0, std::floor(v_min) - 1));
  r.v1 = static_cast<int>(std::min(k.height - 1.0, std::ceil(v_max) + 1));
  return r;
}

// The movers over the static world's frame in `out`: the rays of the pixels that can meet a
// mover (each mover's image rectangle) traced against the movers alone; a mover nearer than what
// the world put on the pixel takes it (nearer than min_range it hides what is behind it, as any
// surface does). Where the world left no return, its ray is traced again to know whether it was
// open sky or a surface too near.
void OverlayMovers(const DepthCamera& camera, const MovingScene::Impl& m, const Eigen::Isometry3d& X_WC,
                   DepthImage* out) {
  const CameraIntrinsics& k = camera.intrinsics();
  const Eigen::Isometry3d X_CW = X_WC.inverse();
  std::vector<PixelRect> rects;
  for (const Eigen::AlignedBox3d& box : m.bounds_W) {
    const PixelRect r = ImageOf(box, X_CW, k);
    if (r.u0 <= r.u1 && r.v0 <= r.v1) rects.push_back(r);
  }
  if (rects.empty()) return;
  const PixelRays rays(k);
  const CameraRayFrame frame(X_WC);
  const std::vector<const std::vector<Eigen::Vector4d>*> world_planes = {&m.world->impl().planes};
  const auto setup = [&](RTCScene scene, const std::vector<const std::vector<Eigen::Vector4d>*>& planes) {
    return RenderSetup{scene,   planes, rays, frame, k.width, k.height, static_cast<float>(k.min_range),
                       static_cast<float>(k.max_range), out->data.data(), frame.origin.cast<double>()};
  };
  const RenderSetup movers = setup(m.movers, m.planes), world = setup(m.world->impl().scene, world_planes);
  std::vector<bool> traced(rects.size() > 1 ? static_cast<std::size_t>(k.width) * k.height : 0);
  FlushDenormalsScope flush;
  RTCIntersectContext context = CoherentContext();
  RTCRayHit rh;
  for (const PixelRect& r : rects) {
    for (int v = r.v0; v <= r.v1; ++v) {
      for (int u = r.u0; u <= r.u1; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * k.width + u;
        if (!traced.empty()) {
          if (traced[i]) continue;  // in an earlier mover's rectangle too
          traced[i] = true;
        }
        FillRay(movers, u, v, &rh.ray);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m.movers, &context, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        const float t = HitDistance(movers, rh.hit.geomID, rh.hit.primID, rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z,
                                    rh.ray.tfar);
        float& pixel = out->data[i];
        float behind = pixel;  // what the world put there
        if (pixel == DepthImage::kNoReturn) {
          FillRay(world, u, v, &rh.ray);
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(world.scene, &context, &rh);
          behind = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID
                       ? std::numeric_limits<float>::infinity()
                       : HitDistance(world, rh.hit.geomID, rh.hit.primID, rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z,
                                     rh.ray.tfar);
        }
        if (t < behind) pixel = DepthOrNoReturn(true, t, movers.min_range, movers.max_range);
      }
    }
  }
  ThrowIfEmbreeError(m.device, "rtcIntersect1");
}

}  // namespace

const char* ToString(EmbreeRayMode mode) {
  switch (mode) {
    case EmbreeRayMode::kSingle: return "single";
    case EmbreeRayMode::kPacket4: return "packet4";
    case EmbreeRayMode::kPacket8: return "packet8";
    case EmbreeRayMode::kPacket16: return "packet16";
    case EmbreeRayMode::kStream: return "stream";
  }
  return "?";
}

void CheckIntrinsics(const CameraIntrinsics& k) {
  auto fail = [](const std::string& field, const std::string& reason) {
    throw std::invalid_argument("CameraIntrinsics." + field + ": " + reason);
  };
  if (k.width <= 0) fail("width", "must be > 0, got " + std::to_string(k.width));
  if (k.height <= 0) fail("height", "must be > 0, got " + std::to_string(k.height));
  if (!(k.fx > 0.0) || !std::isfinite(k.fx)) fail("fx", "must be finite and > 0, got " + std::to_string(k.fx));
  if (!(k.fy > 0.0) || !std::isfinite(k.fy)) fail("fy", "must be finite and > 0, got " + std::to_string(k.fy));
  if (!std::isfinite(k.cx)) fail("cx", "must be finite");
  if (!std::isfinite(k.cy)) fail("cy", "must be finite");
  if (!(k.min_range >= 0.0)) fail("min_range", "must be >= 0, got " + std::to_string(k.min_range));
  if (!(k.max_range > k.min_range) || !std::isfinite(k.max_range)) {
    fail("max_range", "must be finite and > min_range (" + std::to_string(k.min_range) +
                          "), got " + std::to_string(k.max_range));
  }
}

DepthCamera::DepthCamera(const CameraIntrinsics& intrinsics, const DepthNoise& noise,
                         EmbreeRayMode mode)
    : intrinsics_(intrinsics), noise_(noise), mode_(mode) {
  CheckIntrinsics(intrinsics_);
  if (!(noise_.k >= 0.0) || !std::isfinite(noise_.k)) {
    throw std::invalid_argument("DepthNoise.k: must be finite and >= 0, got " +
                                std::to_string(noise_.k));
  }
}

void DepthCamera::Render(const EmbreeScene& scene, const Eigen::Isometry3d& X_WC,
                         DepthImage* out, std::uint64_t noise_seed) const {
  const std::vector<const std::vector<Eigen::Vector4d>*> planes = {&scene.impl().planes};
  Trace(*this, scene.impl().scene, scene.impl().device, planes, X_WC, out);
  ApplyDepthNoise(noise_, intrinsics_, noise_seed, out);
}

void DepthCamera::Render(const MovingScene& scene, const Eigen::Isometry3d& X_WC, DepthImage* out,
                         std::uint64_t noise_seed) const {
  // The static world exactly as without movers, then the movers where they can be seen.
  const MovingScene::Impl& m = scene.impl();
  const std::vector<const std::vector<Eigen::Vector4d>*> planes = {&m.world->impl().planes};
  Trace(*this, m.world->impl().scene, m.world->impl().device, planes, X_WC, out);
  OverlayMovers(*this, m, X_WC, out);
  ApplyDepthNoise(noise_, intrinsics_, noise_seed, out);
}

void ApplyDepthNoise(const DepthNoise& noise, const CameraIntrinsics& intrinsics,
                     std::uint64_t seed, DepthImage* image) {
  if (noise.k == 0.0) return;
  std::mt19937_64 rng(seed);
  const float min_range = static_cast<float>(intrinsics.min_range);
  const float max_range = static_cast<float>(intrinsics.max_range);
  const std::size_t n = image->data.size();
  // Marsaglia's polar form of Box-Muller on raw 64-bit draws: two standard normals per pair of
  // pixels, no sin/cos. The point in the unit disc is drawn for every pair, valid or not, so a
  // pixel's noise does not depend on which other pixels had a return.
  for (std::size_t i = 0; i < n; i += 2) {
    double x, y, s;
    do {
      x = 2.0 * UnitOpenClosed(rng()) - 1.0;
      y = 2.0 * UnitOpenClosed(rng()) - 1.0;
      s = x * x + y * y;
    } while (s >= 1.0 || s == 0.0);
    const bool any_valid =
        DepthImage::Valid(image->data[i]) || (i + 1 < n && DepthImage::Valid(image->data[i + 1]));
    if (!any_valid) continue;
    const double f = std::sqrt(-2.0 * std::log(s) / s);
    const double g[2] = {x * f, y * f};
    for (std::size_t j = 0; j < 2 && i + j < n; ++j) {
      float& d = image->data[i + j];
      if (!DepthImage::Valid(d)) continue;
      const double noisy = d + noise.k * double(d) * d * g[j];
      d = DepthOrNoReturn(true, static_cast<float>(noisy), min_range, max_range);
    }
  }
}

Eigen::Matrix3d CameraRotationInBody() {
  Eigen::Matrix3d R_BC;
  // Columns: the optical axes x, y, z expressed in B.
  R_BC.col(0) = -Eigen::Vector3d::UnitY();
  R_BC.col(1) = -Eigen::Vector3d::UnitZ();
  R_BC.col(2) = Eigen::Vector3d::UnitX();
  return R_BC;
}

Eigen::Isometry3d CameraPoseInWorld(const Eigen::Isometry3d& X_WB,
                                    const navstack::VehicleParams& vehicle) {
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  X_BC.linear() = CameraRotationInBody();
  X_BC.translation() = vehicle.p_BC;
  return X_WB * X_BC;
}

}  // namespace enavi::sim
