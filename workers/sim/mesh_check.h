#pragma once
// Private to enavi_sim: input validation shared by the Embree scene and the Bullet world.

#include "worlds/mesh.h"

namespace enavi::sim {

/// @throws std::invalid_argument naming `who`, the offending triangle/vertex index and the
/// reason, if an index is out of range or a vertex coordinate is not finite.
void CheckTriangleMesh(const worlds::TriangleMesh& mesh, const char* who);

}  // namespace enavi::sim
