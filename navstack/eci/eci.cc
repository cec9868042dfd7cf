#include "navstack/eci/eci.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "navstack/common/argument_check.h"

// Why the occlusion rule (EciOptions::count_occluded): with the normalisation of docs/design.md, "Our reading of the paper"
// eci = sum(w Occ) / sum(w) and Occ taken only from the pixels inside each zone and layer, a
// wall filling the view at range r occupies one layer only, and layer 0 = [0, d0) is empty by
// construction (d0 is the nearest return). So a wall at 0.4 m scores 0.28 while one at 2 m
// scores 0.40: eci would fall as an obstacle comes closer. Counting a zone of layer k occupied
// when most of its pixels already returned from nearer layers (the vehicle cannot pass through,
// the camera cannot see into it) restores the paper's intent: the same wall scores 1.0 inside
// d_min, 0.68 at 1 m, 0.54 at 1.5 m, 0.40 at 2 m, 0.32 at 3 m, lower beyond, and 0 from
// d_per / 2 on (the mid-depth 2 d0 of the obstacle's layer reaches d_per: weight 0).

namespace enavi::navstack {
namespace {

constexpr int kMaxLayers = 64;
// Widest vector any kernel variant uses; buffers are padded to it.
constexpr int kMaxLanes = 8;

#define ENAVI_INLINE inline __attribute__((always_inline))

// Explicit vectors of L floats / int32 (GCC/Clang vector extensions): L = 8 in the AVX2 build of
// the kernels, L = 4 (SSE2, NEON) otherwise. Wider vectors buy nothing here (Zen 4 splits
// 512-bit ops) and narrower ones than the ISA's are lowered badly, so each variant uses its own.
template <int L>
struct Vec;
// (A vector_size depending on a template parameter is not honoured by GCC 12: spell each out.)
#define ENAVI_ECI_VEC(L)                                                            \
  template <>                                                                       \
  struct Vec<L> {                                                                   \
    using F = float __attribute__((vector_size(L * sizeof(float))));                \
    using I = std::int32_t __attribute__((vector_size(L * sizeof(std::int32_t))));  \
    /* Unaligned loads and stores: memcpy compiles to one vector move. */           \
    ENAVI_INLINE static F Load(const float* p) {                                    \
      F v;                                                                          \
      std::memcpy(&v, p, sizeof v);                                                 \
      return v;                                                                     \
    }                                                                               \
    ENAVI_INLINE static I Load(const std::int32_t* p) {                             \
      I v;                                                                          \
      std::memcpy(&v, p, sizeof v);                                                 \
      return v;                                                                     \
    }                                                                               \
    ENAVI_INLINE static void Store(float* p, F v) { std::memcpy(p, &v, sizeof v); } \
    ENAVI_INLINE static void Store(std::int32_t* p, I v) {                          \
      std::memcpy(p, &v, sizeof v);                                                 \
    }                                                                               \
  };
ENAVI_ECI_VEC(4)
ENAVI_ECI_VEC(8)
#undef ENAVI_ECI_VEC

constexpr ArgumentCheck kCheck("EciOptions");

// Squared Euclidean range of a pixel: r^2 = z^2 (1 + x_u^2 + y_v^2) = z^2 (row_c[v] + col_a[u]).
// Every variant, vector or scalar, evaluates it with the same exact float operations (and
// mul/add/compare/min, integer sums), so all give bit-identical results.
struct Image {
  const float* depth;
  int width;
  int height;
  const float* col_a;  // x_u^2, padded with zeros to a multiple of kMaxLanes
  const float* row_c;  // 1 + y_v^2
};

ENAVI_INLINE float Range2(float z, float c, float a) { return (z * z) * (c + a); }

// Pass 1: smallest r^2 over pixels with a return (+inf if none).
template <int L>
ENAVI_INLINE float NearestRange2(const Image& im) {
  using V = Vec<L>;
  const float inf = std::numeric_limits<float>::infinity();
  const typename V::F inf_v = typename V::F{} + inf;
  typename V::F min_v = inf_v;
  float min_s = inf;
  const int full = im.width / L * L;
  for (int v = 0; v < im.height; ++v) {
    const float* row = im.depth + static_cast<std::size_t>(v) * im.width;
    const float c = im.row_c[v];
    for (int u = 0; u < full; u += L) {
      const typename V::F z = V::Load(row + u);
      const typename V::F r2 = (z * z) * (c + V::Load(im.col_a + u));
      const typename V::F m = z > 0.0f ? r2 : inf_v;
      min_v = m < min_v ? m : min_v;
    }
    for (int u = full; u < im.width; ++u) {
      if (row[u] > 0.0f) min_s = std::min(min_s, Range2(row[u], c, im.col_a[u]));
    }
  }
  for (int i = 0; i < L; ++i) min_s = std::min(min_s, min_v[i]);
  return min_s;
}

// Pass 2: for each zone (row band x column run) and threshold j, counts the pixels with
// r^2 >= thresholds[j] (thresholds[0] = 0 counts the returns). Per row, r^2 goes to a buffer
// (no return -> -1, below every threshold); each column run then sweeps it once per threshold
// with a register accumulator, its ragged ends masked to -1. No scatter, no per-pixel branch.
template <int L>
ENAVI_INLINE void CountAboveThresholds(const Image& im, const int* zone_of_row,
                                       const int* col_bounds, int m, const float* thresholds,
                                       int n_thresholds, float* row_buffer,
                                       std::int64_t* counts /* [m * m][n_thresholds] */) {
  using V = Vec<L>;
  using F = typename V::F;
  using I = typename V::I;
  const F minus_one = F{} - 1.0f;
  I lane;
  for (int i = 0; i < L; ++i) lane[i] = i;
  const int padded = (im.width + L - 1) / L * L;
  const int full = im.width / L * L;
  std::fill(row_buffer + full, row_buffer + padded + L, -1.0f);
  // Lane-wise accumulators, L int32 per (zone, threshold).
  std::vector<std::int32_t> acc(static_cast<std::size_t>(m) * m * n_thresholds * L, 0);

  for (int v = 0; v < im.height; ++v) {
    const float* row = im.depth + static_cast<std::size_t>(v) * im.width;
    const float c = im.row_c[v];
    for (int u = 0; u < full; u += L) {
      const F z = V::Load(row + u);
      const F r2 = (z * z) * (c + V::Load(im.col_a + u));
      V::Store(row_buffer + u, z > 0.0f ? r2 : minus_one);
    }
    for (int u = full; u < im.width; ++u) {
      row_buffer[u] = row[u] > 0.0f ? Range2(row[u], c, im.col_a[u]) : -1.0f;
    }

    const int zr = zone_of_row[v];
    for (int zc = 0; zc < m; ++zc) {
      const int b = col_bounds[zc];
      const int e = col_bounds[zc + 1];
      if (b >= e) continue;
      // Whole chunks [fb, fe); partial chunks at either end become masked `lead` / `tail`.
      const int fb = (b + L - 1) / L * L;
      const int fe = e / L * L;
      F lead = minus_one;
      F tail = minus_one;
      int first = fb;
      int last = fe;
      if (fb > fe) {  // the run lies inside one chunk
        const int base = b / L * L;
        lead = ((lane >= b - base) & (lane < e - base)) ? V::Load(row_buffer + base) : minus_one;
        first = last = 0;
      } else {
        if (b < fb) lead = lane >= b - (fb - L) ? V::Load(row_buffer + fb - L) : minus_one;
        if (fe < e) tail = lane < e - fe ? V::Load(row_buffer + fe) : minus_one;
      }
      std::int32_t* zone_acc = acc.data() + static_cast<std::size_t>(zr * m + zc) * n_thresholds * L;
      for (int j = 0; j < n_thresholds; ++j) {
        const float t = thresholds[j];
        I s = (lead >= t) + (tail >= t);  // -1 per lane that passes
        for (int u = first; u < last; u += L) s += V::Load(row_buffer + u) >= t;
        V::Store(zone_acc + j * L, V::Load(zone_acc + j * L) - s);
      }
    }
  }
  for (std::size_t i = 0; i < acc.size() / L; ++i) {
    std::int64_t sum = 0;
    for (int l = 0; l < L; ++l) sum += acc[i * L + l];
    counts[i] = sum;
  }
}

struct Kernels {
  float (*nearest_range2)(const Image&);
  void (*count_above)(const Image&, const int*, const int*, int, const float*, int, float*,
                      std::int64_t*);
};

float NearestRange2Base(const Image& im) { return NearestRange2<4>(im); }
void CountAboveBase(const Image& im, const int* zr, const int* cb, int m, const float* t, int n,
                    float* buf, std::int64_t* counts) {
  CountAboveThresholds<4>(im, zr, cb, m, t, n, buf, counts);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx2"))) float NearestRange2Avx2(const Image& im) {
  return NearestRange2<8>(im);
}
__attribute__((target("avx2"))) void CountAboveAvx2(const Image& im, const int* zr, const int* cb,
                                                    int m, const float* t, int n, float* buf,
                                                    std::int64_t* counts) {
  CountAboveThresholds<8>(im, zr, cb, m, t, n, buf, counts);
}
#endif

const Kernels kBaselineKernels{NearestRange2Base, CountAboveBase};

// The kernel variant for this host, chosen once.
const Kernels& SelectKernels() {
  static const Kernels kernels = [] {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (__builtin_cpu_supports("avx2")) return Kernels{NearestRange2Avx2, CountAboveAvx2};
#endif
    return kBaselineKernels;
  }();
  return kernels;
}

// Zone boundaries along one image axis: bounds[0] = 0, bounds[m] = n, zone i covers pixels
// [bounds[i], bounds[i+1]). Zones have equal angle `fov / m`; the centre zone is centred on
// angle `centre`, pixels beyond the outer zones belong to the edge zones.
std::vector<int> ZoneBounds(int n, double f, double c, double angle_lo, double angle_hi,
                            double centre, int m) {
  const double width = (angle_hi - angle_lo) / m;
  std::vector<int> bounds(m + 1);
  bounds[0] = 0;
  bounds[m] = n;
  for (int i = 1; i < m; ++i) {
    const double b = centre + (i - 0.5 * m) * width;
    int first;  // first pixel whose ray angle is >= b: x_p = (p + 0.5 - c) / f >= tan(b)
    if (b >= 0.5 * M_PI) {
      first = n;
    } else if (b <= -0.5 * M_PI) {
      first = 0;
    } else {
      const double t = std::tan(b);
      first = 0;
      while (first < n && (first + 0.5 - c) / f < t) ++first;
    }
    bounds[i] = std::max(first, bounds[i - 1]);
  }
  return bounds;
}

}  // namespace

void EciOptions::Validate() const {
  kCheck.Range(zones >= 1 && zones <= 15 && zones % 2 == 1, "zones", zones, "odd in [1, 15]");
  kCheck.Range(sigma > 0.0 && sigma <= 100.0, "sigma", sigma, "(0, 100]");
  kCheck.Range(d_per <= 1000.0, "d_per", d_per, "<= 0 (use the camera's max range) or (0, 1000]");
  kCheck.Range(d_min > 0.0 && (d_per <= 0.0 || d_min <= d_per), "d_min", d_min, "(0, d_per]");
  kCheck.Range(min_pixels >= 1 && min_pixels <= 1000000000, "min_pixels", min_pixels, "[1, 1e9]");
  kCheck.Range(occluded_fraction > 0.0 && occluded_fraction <= 1.0, "occluded_fraction",
          occluded_fraction, "(0, 1]");
  kCheck.Range(hover_speed >= 0.0 && hover_speed <= 100.0, "hover_speed", hover_speed, "[0, 100]");
}

namespace {

EciResult ComputeEciWith(const Kernels& kernels, const DepthImage& depth,
                         const CameraIntrinsics& k, const Eigen::Vector3d& v_C,
                         const EciOptions& options, WorkCounts* work) {
  options.Validate();
  if (depth.width != k.width || depth.height != k.height ||
      depth.data.size() != static_cast<std::size_t>(depth.width) * depth.height ||
      depth.width <= 0 || depth.height <= 0) {
    throw std::logic_error("ComputeEci: depth image " + std::to_string(depth.width) + "x" +
                           std::to_string(depth.height) + " does not match the intrinsics " +
                           std::to_string(k.width) + "x" + std::to_string(k.height));
  }
  const double d_per = options.d_per > 0.0 ? options.d_per : k.max_range;
  if (!(options.d_min <= d_per) || !(d_per > 0.0)) {
    throw std::invalid_argument("EciOptions.d_min: " + std::to_string(options.d_min) +
                                " is out of range (0, d_per = " + std::to_string(d_per) + "]");
  }
  if (std::floor((d_per - options.d_min) / (2.0 * options.d_min)) + 1 > kMaxLayers) {
    throw std::invalid_argument("EciOptions.d_min: " + std::to_string(options.d_min) +
                                " gives more than 64 layers at d_per = " + std::to_string(d_per));
  }
  const int W = depth.width;
  const int H = depth.height;
  const int M = options.zones;
  if (work != nullptr) work->Add(WorkUnit::kPixel, std::int64_t{W} * H);

  // Per-column and per-row tables of the range formula.
  const int padded = (W + kMaxLanes - 1) / kMaxLanes * kMaxLanes;
  std::vector<float> col_a(padded, 0.0f), row_c(H);
  for (int u = 0; u < W; ++u) {
    const double x = (u + 0.5 - k.cx) / k.fx;
    col_a[u] = static_cast<float>(x * x);
  }
  for (int v = 0; v < H; ++v) {
    const double y = (v + 0.5 - k.cy) / k.fy;
    row_c[v] = static_cast<float>(1.0 + y * y);
  }
  const Image im{depth.data.data(), W, H, col_a.data(), row_c.data()};

  EciResult result;
  result.zones = M;
  result.d0 = d_per;
  result.d_ahead = d_per;
  result.layers = 1;

  // d0: nearest return, clamped to [d_min, d_per].
  const float nearest2 = kernels.nearest_range2(im);
  if (!(static_cast<double>(nearest2) < d_per * d_per)) return result;  // kNoObstacle, eci = 0
  result.status = EciResult::Status::kOk;
  const double nearest = std::sqrt(static_cast<double>(nearest2));
  const double d0 = std::clamp(nearest, options.d_min, d_per);
  // Lay = floor((d_per - d0) / (2 d0)) + 1 (paper Eq. 2), but at least 2: layer 0 = [0, d0) is
  // empty by construction, so the layer holding the nearest obstacle must exist, or every
  // obstacle beyond d_per / 3 would score 0 (our reading, docs/design.md, "Our reading of the paper").
  const int lay = std::max(2, static_cast<int>(std::floor((d_per - d0) / (2.0 * d0))) + 1);
  result.d0 = d0;
  result.d_ahead = d0;
  result.layers = lay;

  // Layer edges as r^2 thresholds: [0] = 0 (any return), [j] = ((2j - 1) d0)^2 for j = 1..Lay;
  // the last one is the outer edge of the last layer. An unclamped d0 keeps the nearest return
  // exactly on edge 1, in layer 1 = [d0, 3 d0).
  std::vector<float> thresholds(lay + 1);
  thresholds[0] = 0.0f;
  for (int j = 1; j <= lay; ++j) {
    thresholds[j] = static_cast<float>((2.0 * j - 1.0) * (2.0 * j - 1.0) * d0 * d0);
  }
  if (d0 == nearest) thresholds[1] = nearest2;

  // Angular zones: the centre zone on the velocity direction, clamped into the field of view.
  const double az_lo = std::atan((0.0 - k.cx) / k.fx), az_hi = std::atan((W - k.cx) / k.fx);
  const double el_lo = std::atan((0.0 - k.cy) / k.fy), el_hi = std::atan((H - k.cy) / k.fy);
  double az_c = 0.0, el_c = 0.0;
  if (v_C.norm() >= options.hover_speed && v_C.z() > 0.0 && v_C.norm() > 0.0) {
    az_c = std::clamp(std::atan2(v_C.x(), v_C.z()), az_lo, az_hi);
    el_c = std::clamp(std::atan2(v_C.y(), v_C.z()), el_lo, el_hi);
    result.velocity_aligned = true;
  }
  const std::vector<int> col_bounds = ZoneBounds(W, k.fx, k.cx, az_lo, az_hi, az_c, M);
  const std::vector<int> row_bounds = ZoneBounds(H, k.fy, k.cy, el_lo, el_hi, el_c, M);
  std::vector<int> zone_of_row(H);
  for (int r = 0; r < M; ++r) {
    std::fill(zone_of_row.begin() + row_bounds[r], zone_of_row.begin() + row_bounds[r + 1], r);
  }

  const int n_thr = lay + 1;
  std::vector<std::int64_t> above(static_cast<std::size_t>(M) * M * n_thr);
  std::vector<float> row_buffer(padded + kMaxLanes);
  kernels.count_above(im, zone_of_row.data(), col_bounds.data(), M, thresholds.data(), n_thr,
                       row_buffer.data(), above.data());

  // Occupancy and weights. Zones without pixels (outside the image after the centre shift) are
  // not observed and take no part in the sums.
  const double half = 0.5 * (M - 1);
  const double norm = 1.0 / (options.sigma * std::sqrt(2.0 * M_PI));
  double sum_w = 0.0, sum_w_occ = 0.0;
  result.occupancy.assign(static_cast<std::size_t>(lay) * M * M, 0);
  result.pixel_counts.assign(static_cast<std::size_t>(lay) * M * M, 0);
  for (int zr = 0; zr < M; ++zr) {
    for (int zc = 0; zc < M; ++zc) {
      const std::int64_t zone_pixels = std::int64_t{row_bounds[zr + 1] - row_bounds[zr]} *
                                       (col_bounds[zc + 1] - col_bounds[zc]);
      const std::int64_t* c = above.data() + static_cast<std::size_t>(zr * M + zc) * n_thr;
      result.valid_pixels += c[0];
      if (zone_pixels == 0) continue;
      const double theta = zc - half, beta = zr - half;
      const double w_angle =
          norm * std::exp(-(theta * theta + beta * beta) / (4.0 * options.sigma * options.sigma));
      for (int layer = 0; layer < lay; ++layer) {
        const std::int64_t in_layer = c[layer] - c[layer + 1];
        const std::int64_t nearer = c[0] - c[layer];
        const bool occ = in_layer >= options.min_pixels ||
                         (options.count_occluded &&
                          static_cast<double>(nearer) >= options.occluded_fraction * zone_pixels);
        const double d_k = layer == 0 ? 0.5 * d0 : 2.0 * layer * d0;
        const double w = std::max(0.0, (d_per - d_k) / d_per) * w_angle;
        sum_w += w;
        if (occ) {
          sum_w_occ += w;
          ++result.occupied_zones;
        }
        const std::size_t idx = (static_cast<std::size_t>(layer) * M + zr) * M + zc;
        result.occupancy[idx] = occ ? 1 : 0;
        result.pixel_counts[idx] = static_cast<std::int32_t>(in_layer);
      }
    }
  }
  result.eci = sum_w > 0.0 ? sum_w_occ / sum_w : 0.0;
  // Nearest return ahead: one more pass over the centre zone's pixels (1/M^2 of the image).
  if (result.velocity_aligned) {
    const int centre = M / 2;
    float ahead2 = std::numeric_limits<float>::infinity();
    for (int v = row_bounds[centre]; v < row_bounds[centre + 1]; ++v) {
      const float* row = depth.data.data() + static_cast<std::size_t>(v) * W;
      for (int u = col_bounds[centre]; u < col_bounds[centre + 1]; ++u) {
        if (row[u] > 0.0f) ahead2 = std::min(ahead2, Range2(row[u], row_c[v], col_a[u]));
      }
    }
    if (work != nullptr) {
      work->Add(WorkUnit::kPixel, std::int64_t{row_bounds[centre + 1] - row_bounds[centre]} *
                                      (col_bounds[centre + 1] - col_bounds[centre]));
    }
    result.d_ahead = std::min(d_per, std::sqrt(static_cast<double>(ahead2)));
  }
  return result;
}

}  // namespace

EciResult ComputeEci(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                     const Eigen::Vector3d& v_C, const EciOptions& options, WorkCounts* work) {
  return ComputeEciWith(SelectKernels(), depth, intrinsics, v_C, options, work);
}

namespace internal {
EciResult ComputeEciBaseline(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                             const Eigen::Vector3d& v_C, const EciOptions& options) {
  return ComputeEciWith(kBaselineKernels, depth, intrinsics, v_C, options, nullptr);
}
}  // namespace internal

double EciTracker::Update(double eci) {
  d_eci_ = has_previous_ ? eci - eci_ : 0.0;
  eci_ = eci;
  has_previous_ = true;
  return d_eci_;
}

void EciTracker::Reset() {
  eci_ = 0.0;
  d_eci_ = 0.0;
  has_previous_ = false;
}

}  // namespace enavi::navstack
