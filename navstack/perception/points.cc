#include "navstack/perception/points.h"

#include <stdexcept>
#include <string>

#include "navstack/common/argument_check.h"

namespace enavi::navstack {
namespace {

constexpr ArgumentCheck kCheck("PerceptionOptions");

}  // namespace

void PerceptionOptions::Validate() const {
  kCheck.Range(stride >= 1 && stride <= 64, "stride", stride, "[1, 64]");
  kCheck.Range(max_range > 0.0 && max_range <= 100.0, "max_range", max_range, "(0, 100]");
  kCheck.Range(min_range >= 0.0 && min_range < max_range, "min_range", min_range, "[0, max_range)");
}

ScanPoints BackProject(const DepthFrame& frame, const CameraIntrinsics& intrinsics,
                       const PerceptionOptions& options, WorkCounts* work) {
  options.Validate();
  const DepthImage& image = frame.image;
  if (image.width != intrinsics.width || image.height != intrinsics.height ||
      image.data.size() != static_cast<std::size_t>(image.width) * image.height) {
    throw std::logic_error("BackProject: depth image " + std::to_string(image.width) + "x" +
                           std::to_string(image.height) + " does not match the intrinsics " +
                           std::to_string(intrinsics.width) + "x" +
                           std::to_string(intrinsics.height));
  }
  const int s = options.stride;
  const int cols = (image.width + s - 1) / s;
  const int rows = (image.height + s - 1) / s;

  ScanPoints scan;
  scan.origin_W = frame.X_WC.translation();
  scan.hits_W.reserve(static_cast<std::size_t>(cols) * rows);

  // Ray of pixel (u, v) at unit depth is (x_u, y_v, 1); tabulate x_u once per column.
  std::vector<double> x_of_col(cols);
  for (int i = 0; i < cols; ++i) x_of_col[i] = (i * s + 0.5 - intrinsics.cx) / intrinsics.fx;

  const Eigen::Matrix3d R_WC = frame.X_WC.linear();
  const Eigen::Vector3d& p_WC = scan.origin_W;
  const float min_z = static_cast<float>(options.min_range);
  const float max_z = static_cast<float>(options.max_range);
  for (int j = 0; j < rows; ++j) {
    const int v = j * s;
    const double y = (v + 0.5 - intrinsics.cy) / intrinsics.fy;
    const float* row = image.data.data() + static_cast<std::size_t>(v) * image.width;
    for (int i = 0; i < cols; ++i) {
      const float z = row[i * s];
      std::vector<Eigen::Vector3f>* out;
      double depth;
      if (!DepthImage::Valid(z)) {
        out = &scan.no_return_W;
        depth = options.max_range;
      } else if (z < min_z) {
        continue;  // too close to trust: neither a surface nor free space
      } else if (z > max_z) {
        out = &scan.far_W;
        depth = options.max_range;
      } else {
        out = &scan.hits_W;
        depth = z;
      }
      const Eigen::Vector3d p_C(x_of_col[i] * depth, y * depth, depth);
      out->push_back((p_WC + R_WC * p_C).cast<float>());
    }
  }
  if (work != nullptr) work->Add(WorkUnit::kBackProjection, static_cast<std::int64_t>(cols) * rows);
  return scan;
}

}  // namespace enavi::navstack
