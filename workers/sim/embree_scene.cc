#include "workers/sim/embree_scene.h"

#include <cpuid.h>

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "workers/sim/embree_impl.h"
#include "workers/sim/mesh_check.h"

namespace enavi::sim {
namespace {

const char* ErrorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
  }
  return "RTC_ERROR_?";
}

// Embree reports errors through this callback on the thread that made the failing call. Throwing
// through Embree's C API is not safe, so the message is kept here and ThrowIfEmbreeError, called
// right after each Embree call that can fail, turns it into an exception.
thread_local std::string t_last_embree_message;

void RecordEmbreeError(void* /*user*/, RTCError code, const char* message) {
  t_last_embree_message = std::string(ErrorName(code)) + ": " + (message ? message : "");
}

}  // namespace

void ThrowIfEmbreeError(RTCDevice device, const char* call) {
  const RTCError code = rtcGetDeviceError(device);
  if (code == RTC_ERROR_NONE) return;
  std::string message = std::move(t_last_embree_message);
  t_last_embree_message.clear();
  if (message.empty()) message = ErrorName(code);
  throw std::runtime_error(std::string("Embree error in ") + call + ": " + message);
}

std::string RayKernels() {
  // The features of Embree's AVX2 target, the cap's level. GCC's checks include the OS's YMM
  // state (XGETBV), as Embree's own does.
  static_assert(std::string_view(kEmbreeMaxIsa) == "avx2", "RayKernels checks the AVX2 features");
  // Clang's __builtin_cpu_supports has no "lzcnt": that bit is read from CPUID directly
  // (leaf 0x80000001, ECX bit 5).
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  const bool lzcnt = __get_cpuid(0x80000001u, &eax, &ebx, &ecx, &edx) && (ecx & bit_LZCNT) != 0;
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                    __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2") && lzcnt;
  return avx2 ? kEmbreeMaxIsa : "sse-avx";
}

// ---------------------------------------------------------------------------------------------
// EmbreeDevice

EmbreeDevice::EmbreeDevice(const std::string& max_isa) : impl_(std::make_unique<Impl>()) {
  const std::string config = "verbose=0,max_isa=" + max_isa;
  impl_->device = rtcNewDevice(config.c_str());
  if (impl_->device == nullptr) {
    throw std::runtime_error(std::string("Embree error in rtcNewDevice: ") +
                             ErrorName(rtcGetDeviceError(nullptr)));
  }
  rtcSetDeviceErrorFunction(impl_->device, &RecordEmbreeError, nullptr);
}

EmbreeDevice::~EmbreeDevice() {
  if (impl_ && impl_->device) rtcReleaseDevice(impl_->device);
}

const EmbreeDevice& EmbreeDevice::Get() {
  // C++ guarantees thread-safe initialisation of a function-local static.
  static const EmbreeDevice device(kEmbreeMaxIsa);
  return device;
}

EmbreeDeviceInfo EmbreeDevice::Info() const {
  RTCDevice d = impl_->device;
  EmbreeDeviceInfo info;
  info.version = std::to_string(rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_VERSION_MAJOR)) + "." +
                 std::to_string(rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_VERSION_MINOR)) + "." +
                 std::to_string(rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_VERSION_PATCH));
  info.native_ray4 = rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) != 0;
  info.native_ray8 = rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0;
  info.native_ray16 = rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  info.ray_stream = rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED) != 0;
  switch (rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_TASKING_SYSTEM)) {
    case 0: info.tasking = "internal"; break;
    case 1: info.tasking = "tbb"; break;
    case 2: info.tasking = "ppl"; break;
    default: info.tasking = "unknown"; break;
  }
  info.ray_kernels = RayKernels();
  ThrowIfEmbreeError(d, "rtcGetDeviceProperty");
  return info;
}

// ---------------------------------------------------------------------------------------------
// EmbreeScene

EmbreeScene::Impl::~Impl() {
  if (scene) rtcReleaseScene(scene);
}

EmbreeScene::EmbreeScene(const worlds::TriangleMesh& mesh, const EmbreeSceneOptions& options,
                         const EmbreeDevice& embree_device)
    : impl_(std::make_unique<Impl>()) {
  CheckTriangleMesh(mesh, "EmbreeScene");
  RTCDevice device = embree_device.impl().device;
  impl_->device = device;
  const RTCBuildQuality quality =
      options.high_quality ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;

  impl_->scene = rtcNewScene(device);
  ThrowIfEmbreeError(device, "rtcNewScene");
  rtcSetSceneFlags(impl_->scene, options.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(impl_->scene, quality);
  ThrowIfEmbreeError(device, "rtcSetSceneBuildQuality");

  // An empty world is a valid scene in which every ray misses.
  if (!mesh.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    ThrowIfEmbreeError(device, "rtcNewGeometry");
    rtcSetGeometryBuildQuality(geometry, quality);
    // Embree-allocated buffers carry the padding its SIMD loads need past the last vertex.
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
        mesh.vertices.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
        mesh.triangles.size()));
    if (vertices == nullptr || indices == nullptr) {
      rtcReleaseGeometry(geometry);
      ThrowIfEmbreeError(device, "rtcSetNewGeometryBuffer");
      throw std::runtime_error("Embree error in rtcSetNewGeometryBuffer: no buffer returned");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) vertices[3 * i + k] = mesh.vertices[i][k];
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) indices[3 * i + k] = static_cast<unsigned>(mesh.triangles[i][k]);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
    ThrowIfEmbreeError(device, "rtcAttachGeometry");
  }
  rtcCommitScene(impl_->scene);
  ThrowIfEmbreeError(device, "rtcCommitScene");

  impl_->triangle_count = mesh.triangles.size();
  impl_->planes.reserve(mesh.triangles.size());
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[tri[0]].cast<double>();
    const Eigen::Vector3d n =
        (mesh.vertices[tri[1]].cast<double>() - a).cross(mesh.vertices[tri[2]].cast<double>() - a);
    impl_->planes.emplace_back(n.x(), n.y(), n.z(), n.dot(a));
  }
  if (!mesh.triangles.empty()) {
    RTCBounds b;
    rtcGetSceneBounds(impl_->scene, &b);
    ThrowIfEmbreeError(device, "rtcGetSceneBounds");
    impl_->bounds = Eigen::AlignedBox3f(Eigen::Vector3f(b.lower_x, b.lower_y, b.lower_z),
                                        Eigen::Vector3f(b.upper_x, b.upper_y, b.upper_z));
  }
}

EmbreeScene::~EmbreeScene() = default;
EmbreeScene::EmbreeScene(EmbreeScene&&) noexcept = default;
EmbreeScene& EmbreeScene::operator=(EmbreeScene&&) noexcept = default;

std::size_t EmbreeScene::triangle_count() const { return impl_->triangle_count; }
Eigen::AlignedBox3f EmbreeScene::bounds() const { return impl_->bounds; }

}  // namespace enavi::sim
