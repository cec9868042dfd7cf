#pragma once
// For tests only: eci with the portable 4-lane kernel forced, whatever the host supports.

#include "navstack/eci/eci.h"

namespace enavi::navstack::internal {

/// ComputeEci with the baseline (SSE2/NEON-width) kernel; must equal ComputeEci bit for bit.
EciResult ComputeEciBaseline(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                             const Eigen::Vector3d& v_C, const EciOptions& options = {});

}  // namespace enavi::navstack::internal
