#include "navstack/perception/difference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "navstack/common/argument_check.h"

namespace enavi::navstack {
namespace {

constexpr ArgumentCheck kCheck("DifferenceOptions");

void RequireMatches(const DepthImage& image, const CameraIntrinsics& k, const char* which) {
  if (image.width != k.width || image.height != k.height ||
      image.data.size() != static_cast<std::size_t>(image.width) * image.height) {
    throw std::logic_error(std::string("DetectDifference: ") + which + " image " +
                           std::to_string(image.width) + "x" + std::to_string(image.height) +
                           " does not match the intrinsics " + std::to_string(k.width) + "x" +
                           std::to_string(k.height));
  }
}

constexpr float kNoPrediction = -1.0f;
constexpr float kNoReturn = std::numeric_limits<float>::infinity();

}  // namespace

void DifferenceOptions::Validate() const {
  kCheck.Range(stride >= 1 && stride <= 64, "stride", stride, "[1, 64]");
  kCheck.Range(relevant_depth > 0.0 && relevant_depth <= 100.0, "relevant_depth", relevant_depth,
          "(0, 100]");
  kCheck.Range(abs_tolerance >= 0.0 && abs_tolerance <= 10.0, "abs_tolerance", abs_tolerance, "[0, 10]");
  kCheck.Range(rel_tolerance >= 0.0 && rel_tolerance <= 1.0, "rel_tolerance", rel_tolerance, "[0, 1]");
  kCheck.Range(trigger_fraction > 0.0 && trigger_fraction <= 1.0, "trigger_fraction", trigger_fraction,
          "(0, 1]");
}

DifferenceResult DetectDifference(const DepthFrame& previous, const DepthFrame& current,
                                  const CameraIntrinsics& k, const DifferenceOptions& options,
                                  WorkCounts* work) {
  options.Validate();
  RequireMatches(previous.image, k, "previous");
  RequireMatches(current.image, k, "current");
  const int s = options.stride;
  const int cols = (k.width + s - 1) / s;
  const int rows = (k.height + s - 1) / s;

  std::vector<double> x_of_col(cols), y_of_row(rows);
  for (int i = 0; i < cols; ++i) x_of_col[i] = (i * s + 0.5 - k.cx) / k.fx;
  for (int j = 0; j < rows; ++j) y_of_row[j] = (j * s + 0.5 - k.cy) / k.fy;

  // Forward-warp the previous samples into the current camera, keeping the nearest depth per
  // sample cell (a z-buffer on the sample grid). No-return pixels are warped as points at the
  // camera's max range and predict "no return" there.
  const Eigen::Isometry3d X_CcCp = current.X_WC.inverse() * previous.X_WC;
  const Eigen::Matrix3d R = X_CcCp.linear();
  const Eigen::Vector3d t = X_CcCp.translation();
  std::vector<float> predicted(static_cast<std::size_t>(cols) * rows, kNoPrediction);
  const double far = k.max_range;
  for (int j = 0; j < rows; ++j) {
    const float* row = previous.image.data.data() + static_cast<std::size_t>(j) * s * k.width;
    for (int i = 0; i < cols; ++i) {
      const float z = row[i * s];
      const bool hit = DepthImage::Valid(z);
      const double depth = hit ? z : far;
      const Eigen::Vector3d p = R * Eigen::Vector3d(x_of_col[i] * depth, y_of_row[j] * depth, depth) + t;
      if (p.z() <= 1e-3) continue;
      // Continuous pixel coordinate, then the nearest sample cell.
      const double u = k.fx * p.x() / p.z() + k.cx - 0.5;
      const double v = k.fy * p.y() / p.z() + k.cy - 0.5;
      const double ci = std::floor(u / s + 0.5);
      const double cj = std::floor(v / s + 0.5);
      if (ci < 0 || cj < 0 || ci >= cols || cj >= rows) continue;
      float& cell = predicted[static_cast<std::size_t>(cj) * cols + static_cast<std::size_t>(ci)];
      const float value = hit ? static_cast<float>(p.z()) : kNoReturn;
      if (cell == kNoPrediction || value < cell) cell = value;
    }
  }

  DifferenceResult result;
  result.sampled = std::int64_t{cols} * rows;
  const float relevant = static_cast<float>(options.relevant_depth);
  for (int j = 0; j < rows; ++j) {
    const float* row = current.image.data.data() + static_cast<std::size_t>(j) * s * k.width;
    for (int i = 0; i < cols; ++i) {
      // Nearest prediction among the 3x3 neighbouring samples absorbs edge and sampling jitter.
      float nearest = kNoPrediction;
      for (int b = std::max(0, j - 1); b <= std::min(rows - 1, j + 1); ++b) {
        for (int a = std::max(0, i - 1); a <= std::min(cols - 1, i + 1); ++a) {
          const float p = predicted[static_cast<std::size_t>(b) * cols + a];
          if (p != kNoPrediction && (nearest == kNoPrediction || p < nearest)) nearest = p;
        }
      }
      if (nearest == kNoPrediction) continue;
      ++result.compared;
      const float z = row[i * s];
      if (!DepthImage::Valid(z) || z >= relevant) continue;
      const bool changed =
          nearest == kNoReturn ||
          z < nearest - std::max(options.abs_tolerance, options.rel_tolerance * nearest);
      if (changed) ++result.changed;
    }
  }
  result.changed_fraction = static_cast<double>(result.changed) / static_cast<double>(result.sampled);
  result.trigger = result.changed_fraction >= options.trigger_fraction;
  if (work != nullptr) work->Add(WorkUnit::kWarpPixel, 2 * result.sampled);
  return result;
}

}  // namespace enavi::navstack
