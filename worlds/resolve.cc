#include "worlds/resolve.h"

#include <filesystem>

#include "worlds/generators.h"
#include "worlds/obj_import.h"
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

}  // namespace

World ResolveWorld(const WorldRequest& request) {
  const std::string& id = request.world;
  const bool is_yaml = EndsWith(id, ".yaml") || EndsWith(id, ".yml");
  const bool is_obj = EndsWith(id, ".obj");
  if ((is_yaml || is_obj) && !request.params.empty()) {
    throw WorldError(id, 0, "params", "generator parameters apply to scenario ids only, not to files");
  }
  if (is_yaml) {
    WorldFileOptions options;
    options.start = request.start;
    options.goal = request.goal;
    return LoadWorldFile(id, options);
  }
  if (is_obj) {
    if (!request.start) throw WorldError(id, 0, "start", "required for an OBJ world (--start x,y,z)");
    if (!request.goal) throw WorldError(id, 0, "goal", "required for an OBJ world (--goal x,y,z)");
    World world = WorldFromObj(id, *request.start, *request.goal);
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
                   "'" + id + "' is neither a scenario (" + ids + ") nor a world file (.yaml, .obj)");
}

}  // namespace enavi::worlds
