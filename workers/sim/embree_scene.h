#pragma once
// Embree 3 device and scene owners. Embree types stay in embree_impl.h (included by our .cc files
// only), so code that includes this header needs neither Embree's headers nor its include path.

#include <cstddef>
#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "worlds/mesh.h"

namespace enavi::sim {

/// What the Embree library in this process can do (for logs and benchmark reports).
struct EmbreeDeviceInfo {
  std::string version;       ///< e.g. "3.13.5"
  bool native_ray4 = false;  ///< rtcIntersect4 runs natively (not emulated by single rays)
  bool native_ray8 = false;
  bool native_ray16 = false;
  bool ray_stream = false;
  std::string tasking;       ///< "internal", "tbb" or "ppl"
  std::string ray_kernels;   ///< RayKernels()
};

/// Embree picks its ray kernels for the widest SIMD instruction set of the host. Kernels of
/// different widths traverse differently built BVHs, and every kernel computes a hit's distance
/// with the CPU's approximate reciprocal (rcpps plus a Newton step), whose last bits the CPU's
/// vendor defines: the same build and kernels flew other flights on an Intel host than on an
/// AMD one (the baseline's s3 on pi4b, seeds 1-3: 17.5 against 21.4 s). So the depth camera takes
/// from Embree only which triangle a ray hits and computes the distance itself
/// (depth_camera.cc). Which triangle a ray grazing an edge hits can still depend on the BVH, so
/// the device is capped at AVX2 (Debian's Embree 3.13.5 also carries AVX-512 kernels) and every
/// host with AVX2 traverses the same one; a host without AVX2 runs the narrower kernels.
inline constexpr const char* kEmbreeMaxIsa = "avx2";

/// The kernels this host runs under that cap: "avx2", or "sse-avx" when the CPU lacks one of the
/// features Embree's AVX2 kernels need (AVX2, FMA3, BMI1, BMI2, LZCNT, with the OS saving YMM).
/// Results of hosts with different kernels may differ where a ray grazes an edge; episodes
/// record the class (provenance.ray_kernels).
std::string RayKernels();

/// The process-wide Embree device. Created on first use (thread-safe), never destroyed before
/// the scenes that use it (Embree reference-counts the device from each scene). Embree errors
/// are recorded by the device's error callback and rethrown by our wrappers as
/// std::runtime_error carrying Embree's message.
class EmbreeDevice {
 public:
  struct Impl;

  /// The one device of this process, capped at kEmbreeMaxIsa.
  static const EmbreeDevice& Get();

  /// A device whose kernels are capped at `max_isa` (Embree's names: "sse2", "sse4.2", "avx",
  /// "avx2", "avx512"; a cap above what the CPU has runs the CPU's widest). Tests render with
  /// each to check that the kernels do not change the image.
  /// @throws std::runtime_error with Embree's message if the device cannot be created.
  explicit EmbreeDevice(const std::string& max_isa);

  EmbreeDeviceInfo Info() const;
  const Impl& impl() const { return *impl_; }

  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;
  ~EmbreeDevice();

 private:
  std::unique_ptr<Impl> impl_;
};

struct EmbreeSceneOptions {
  /// RTC_SCENE_FLAG_ROBUST: no traversal shortcuts that can miss hits on shared edges, so the
  /// camera never sees through the seam between two triangles of a wall. Costs ~25 % of ray
  /// throughput on the synthetic park (38 vs 50 Mrays/s per core on an EPYC Zen 4); without it
  /// a few pixels per million rays came out different by more than 1 mm.
  bool robust = true;
  /// RTC_BUILD_QUALITY_HIGH (spatial splits): slower build once per world, faster rays after.
  bool high_quality = true;
};

/// One committed, static Embree scene holding a world's triangles (copied: the scene owns its
/// data). Move-only. Read-only after construction, so one scene can be shared by any number of
/// threads and episodes rendering at the same time.
class EmbreeScene {
 public:
  struct Impl;

  /// @throws std::invalid_argument if a triangle index is out of range or a vertex is not finite.
  explicit EmbreeScene(const worlds::TriangleMesh& mesh, const EmbreeSceneOptions& options = {},
                       const EmbreeDevice& device = EmbreeDevice::Get());
  ~EmbreeScene();
  EmbreeScene(EmbreeScene&&) noexcept;
  EmbreeScene& operator=(EmbreeScene&&) noexcept;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  std::size_t triangle_count() const;
  /// Axis-aligned bounds of the committed geometry (empty box for an empty mesh).
  Eigen::AlignedBox3f bounds() const;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::sim
