#include "workers/sim/mesh_check.h"

#include <cstdint>
#include <stdexcept>
#include <string>

namespace enavi::sim {

void CheckTriangleMesh(const worlds::TriangleMesh& mesh, const char* who) {
  const auto n = static_cast<std::int64_t>(mesh.vertices.size());
  // Embree and Bullet index with 32-bit integers.
  if (n > INT32_MAX || static_cast<std::int64_t>(mesh.triangles.size()) > INT32_MAX) {
    throw std::invalid_argument(std::string(who) + ": mesh too large (" + std::to_string(n) +
                                " vertices, " + std::to_string(mesh.triangles.size()) +
                                " triangles; limit 2^31 - 1 each)");
  }
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      throw std::invalid_argument(std::string(who) + ": TriangleMesh.vertices[" +
                                  std::to_string(i) + "] is not finite");
    }
  }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= n) {
        throw std::invalid_argument(std::string(who) + ": TriangleMesh.triangles[" +
                                    std::to_string(i) + "][" + std::to_string(k) + "] = " +
                                    std::to_string(t[k]) + " is outside [0, " +
                                    std::to_string(n) + ")");
      }
    }
  }
}

}  // namespace enavi::sim
