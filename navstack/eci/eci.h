#pragma once
// Environment-adaptive spatial Complexity Index, eci (paper Sec. IV; docs/design.md, "Our reading of the paper").

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "navstack/common/camera.h"
#include "navstack/common/work.h"

namespace enavi::navstack {

/// Parameters of eci. The paper's defaults: M = 3, sigma = 1.
struct EciOptions {
  int zones = 3;               ///< M, angular zones per axis; odd so a centre zone exists. [1, 15]
  double sigma = 1.0;          ///< angular sensitivity of the Gaussian weight, in zone units. (0, 100]
  /// d_per, m: maximum perception distance. <= 0 uses intrinsics.max_range. Otherwise (0, 1000]
  double d_per = 0.0;
  /// d_min, m: lower clamp of d0, the nearest obstacle range. It bounds the layer count
  /// (Lay <= floor((d_per - d_min) / (2 d_min)) + 1 = 10 at 10 m) and makes anything nearer than
  /// d_min fall in layer 0, "demanding immediate evasive action". (0, d_per]
  double d_min = 0.5;
  /// Occ(a,k) = 1 when at least this many valid pixels fall in zone a of layer k. 12 on the
  /// default 320x240 stream covers the solid angle of 50 pixels of the full 640x480 frame. [1, 1e9]
  int min_pixels = 12;
  /// Also count a zone of layer k occupied when at least occluded_fraction of the zone's pixels
  /// return from a nearer layer: the camera cannot see into it and the vehicle cannot fly
  /// through it. Without this, a depth image (one return per pixel) can only fill one layer
  /// behind a wall, so a wall at 0.4 m would score lower than one at 2 m. See eci.cc.
  bool count_occluded = true;
  double occluded_fraction = 0.5;  ///< (0, 1]
  /// Below this speed (m/s) the vehicle hovers: the centre zone is the optical axis. [0, 100]
  double hover_speed = 0.2;

  /// Throws std::invalid_argument naming the field and its allowed range.
  void Validate() const;
};

struct EciResult {
  enum class Status { kOk, kNoObstacle };
  Status status = Status::kNoObstacle;  ///< kNoObstacle: no valid pixel within d_per, eci = 0
  double eci = 0.0;                     ///< sum(w Occ) / sum(w), in [0, 1]
  double d0 = 0.0;                      ///< m, nearest obstacle range clamped to [d_min, d_per]
  /// m, the nearest return in the centre zone, the one "oriented along the UAV's velocity vector"
  /// that "represents the most threat" (paper Sec. IV.A), unclamped; d_per when it has none.
  /// d0 when not velocity_aligned (hovering, or moving out of the view: nothing is known ahead).
  double d_ahead = 0.0;
  int layers = 0;                       ///< Lay = floor((d_per - d0) / (2 d0)) + 1
  int zones = 0;                        ///< M
  int occupied_zones = 0;               ///< zones with Occ = 1, of layers x M x M
  std::int64_t valid_pixels = 0;        ///< pixels with a return
  /// Zone of the image the centre zone is aligned to: the velocity direction (true) or the
  /// optical axis (false: hovering or moving away from the view).
  bool velocity_aligned = false;
  /// Occ per zone, index (k * M + row) * M + col; row 0 is the top of the image, col 0 the left.
  std::vector<std::uint8_t> occupancy;
  /// Valid pixels per zone and layer, same indexing as `occupancy`.
  std::vector<std::int32_t> pixel_counts;
};

/// Computes eci of one depth frame.
///
/// Range is the Euclidean distance from the camera centre (the paper's "ranging distance": layers
/// are spherical shells), computed from the z-depth with per-row and per-column tables.
/// Layers: k = 0 is [0, d0), layer k >= 1 is [(2k - 1) d0, (2k + 1) d0); returns beyond the last
/// layer are ignored (the formula for Lay keeps layers inside d_per). Zones: azimuth
/// theta = atan(x/z) and pitch beta = atan(y/z) of the pixel ray, so zones are image rectangles;
/// M x M zones of equal angle (the field of view / M) with the centre zone centred on the
/// velocity direction v_C (clamped into the field of view), pixels beyond the outer zones
/// belonging to the edge zones; a zone left without pixels by the shift is not observed and is
/// left out of both sums. Occ(a, k) = 1 when >= min_pixels returns fall in it, or (with
/// count_occluded) when >= occluded_fraction of the zone's pixels return from nearer layers.
/// Weight of zone (a, k): w = max(0, (d_per - d_k) / d_per) *
/// exp(-(theta_a^2 + beta_a^2) / (4 sigma^2)) / (sigma sqrt(2 pi)), theta_a, beta_a in zone
/// units from the centre zone, d_k the layer's mid-range (d0 / 2, then 2 k d0);
/// eci = sum(w Occ) / sum(w). The centre falls back to the optical axis when |v_C| <
/// hover_speed or v_C points away from the view (v_C.z <= 0). d_ahead takes one more pass over
/// the centre zone's pixels.
/// Counts one WorkUnit::kPixel per image pixel, plus one per centre-zone pixel for d_ahead.
/// @param v_C vehicle velocity in the camera frame C (z forward, x right, y down), m/s.
/// @pre depth matches the intrinsics' size.
EciResult ComputeEci(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                     const Eigen::Vector3d& v_C, const EciOptions& options = {},
                     WorkCounts* work = nullptr);

/// d_eci = eci(t) - eci(t - 1 frame), fed one frame at a time.
class EciTracker {
 public:
  /// Feeds the eci of the next frame; returns d_eci (0 for the first frame after a Reset).
  double Update(double eci);
  double eci() const { return eci_; }
  double d_eci() const { return d_eci_; }
  bool has_previous() const { return has_previous_; }
  void Reset();

 private:
  double eci_ = 0.0;
  double d_eci_ = 0.0;
  bool has_previous_ = false;
};

}  // namespace enavi::navstack
