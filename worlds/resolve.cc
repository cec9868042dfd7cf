#include "worlds/resolve.h"

#include <filesystem>

#include "worlds/generators.h"
#include "worlds/mesh_import.h"
#include "worlds/sdf_import.h"
#include "worlds/validate.h"
#include "worlds/world_io.h"

namespace enavi::worlds {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  for (std::size_t i = 0; i < suffix.size(); ++i) {
    const char c = s[s.size() - suffix.size() + i];
    if ((c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c) != suffix[i]) return false;
  }
  return true;
}

void ValidateOrThrow(const World& world, const std::string& source) {
  const ValidationResult v = ValidateWorld(world);
  if (!v.ok) throw WorldError(source, 0, v.field, v.reason);
}

bool PlacementGiven(const MeshPlacement& p) { return !p.units.empty() || p.up || p.recenter || p.scale != 1.0; }

}  // namespace

World ResolveWorld(const WorldRequest& request) {
  const std::string& id = request.world;
  const bool is_yaml = EndsWith(id, ".yaml") || EndsWith(id, ".yml");
  const bool is_mesh = IsMeshFile(id);
  const bool is_sdf = IsSdfFile(id);
  if ((is_yaml || is_mesh || is_sdf) && !request.params.empty()) {
    throw WorldError(id, 0, "params", "generator parameters apply to scenario ids only, not to files");
  }
  if (!is_mesh && PlacementGiven(request.placement)) {
    throw WorldError(id, 0, "units",
                     "--units, --scale, --up and --recenter apply to mesh files only (a world file places its meshes "
                     "itself; SDF is in metres, z up)");
  }
  if (!is_sdf && !request.model_path.empty()) {
    throw WorldError(id, 0, "model_path", "--model-path applies to SDF worlds only");
  }
  if (is_yaml) {
    WorldFileOptions options;
    options.start = request.start;
    options.goal = request.goal;
    options.load_mesh = LoadMeshFile;
    return LoadWorldFile(id, options);
  }
  if (is_mesh || is_sdf) {
    const char* kind = is_mesh ? "mesh" : "SDF";
    if (!request.start) throw WorldError(id, 0, "start", std::string("required for a ") + kind + " world (--start x,y,z)");
    if (!request.goal) throw WorldError(id, 0, "goal", std::string("required for a ") + kind + " world (--goal x,y,z)");
    World world = is_mesh ? WorldFromMesh(id, LoadMeshFile(id), request.placement, *request.start, *request.goal)
                          : LoadSdfWorld(id, *request.start, *request.goal, request.model_path);
    ValidateOrThrow(world, id);
    return world;
  }
  if (FindGenerator(id) != nullptr) {
    World world = Generate(id, request.seed, request.params);
    if (request.start || request.goal) {
      if (request.start) world.start = *request.start;
      if (request.goal) world.goal = *request.goal;
      ValidateOrThrow(world, id);
    }
    return world;
  }
  std::string ids;
  for (const auto& g : Generators()) ids += (ids.empty() ? "" : ", ") + g.id;
  throw WorldError("", 0, "world",
                   "'" + id + "' is neither a scenario (" + ids + ") nor a world file (.yaml, " + MeshExtensions() +
                       ", .sdf, .world)");
}

}  // namespace enavi::worlds
