#pragma once
// Environment-difference detection: a cheap replan trigger that works on raw depth (paper
// Sec. V.B: "the environment difference detection processes raw sensor data").

#include <cstdint>

#include "navstack/common/camera.h"
#include "navstack/common/work.h"

namespace enavi::navstack {

struct DifferenceOptions {
  int stride = 2;                  ///< pixel stride in both frames (2 on the 320x240 stream). [1, 64]
  /// Only returns nearer than this (z-depth) can count as a change: what the vehicle may reach
  /// before the next plan. m, (0, 100]
  double relevant_depth = 5.0;
  double abs_tolerance = 0.3;      ///< "markedly closer": by more than max(abs, rel x predicted). m, [0, 10]
  double rel_tolerance = 0.1;      ///< see abs_tolerance. [0, 1]
  double trigger_fraction = 0.005; ///< changed / sampled pixels that triggers a replan. (0, 1]

  /// Throws std::invalid_argument naming the field and its allowed range.
  void Validate() const;
};

struct DifferenceResult {
  double changed_fraction = 0.0;   ///< changed / sampled
  bool trigger = false;            ///< changed_fraction >= trigger_fraction
  std::int64_t changed = 0;        ///< sampled pixels of `current` that changed
  std::int64_t compared = 0;       ///< sampled pixels that had a prediction from `previous`
  std::int64_t sampled = 0;        ///< sampled pixels of `current`
};

/// Compares `current` with `previous` warped into the current camera (ego-motion compensated
/// with the two frames' X_WC). A sampled pixel of `current` has changed when it holds a return
/// nearer than relevant_depth that is markedly closer than the nearest prediction in its 3x3
/// neighbourhood of samples, or where the previous frame predicted no return there (a new
/// surface). Pixels with no prediction (entering the view, disocclusions) do not count; surfaces
/// moving away do not count. Counts kWarpPixel for the sampled pixels of both frames.
/// @pre both images match the intrinsics.
DifferenceResult DetectDifference(const DepthFrame& previous, const DepthFrame& current,
                                  const CameraIntrinsics& intrinsics,
                                  const DifferenceOptions& options = {},
                                  WorkCounts* work = nullptr);

}  // namespace enavi::navstack
