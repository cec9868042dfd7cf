// `enavi world gen|check|show`: generate a seeded world file, validate a world, draw a
// bird's-eye PNG. Thin handlers: parse flags, call enavi::worlds / enavi::report, print.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "server/cli/cli_values.h"
#include "server/cli/commands.h"
#include "server/report/top_down.h"
#include "worlds/generators.h"
#include "worlds/mesh.h"
#include "worlds/number_text.h"
#include "worlds/resolve.h"
#include "worlds/validate.h"
#include "worlds/world_convert.h"
#include "worlds/world_io.h"

namespace enavi::cli {
namespace {

// An optional point flag: absent when empty.
std::optional<Eigen::Vector3d> PointFlag(const std::string& flag, const std::string& text) {
  if (text.empty()) return std::nullopt;
  const api::Vec3 p = ParsePoint(flag, text);
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

std::string Vec(const Eigen::Vector3d& v) {
  return "[" + worlds::FormatFixed(v.x(), 2, false) + ", " + worlds::FormatFixed(v.y(), 2, false) + ", " +
         worlds::FormatFixed(v.z(), 2, false) + "]";
}

std::string Summary(const worlds::World& w) {
  return w.metadata.name + " (" + w.metadata.scenario + "), " + std::to_string(w.objects.size()) + " objects, " +
         std::to_string(worlds::BuildWorldMesh(w).triangle_count()) + " triangles, start-goal " +
         worlds::FormatFixed((w.goal - w.start).norm(), 1) + " m, bounds " + Vec(w.bounds.min()) + " to " +
         Vec(w.bounds.max()) + (w.metadata.import_note.empty() ? "" : "; " + w.metadata.import_note);
}

struct WorldFlags {
  std::string scenario;
  std::string target;  // FILE or ID
  std::uint64_t seed = 1;
  std::vector<std::string> params;
  std::string start, goal;
  std::string units, up;
  double scale = 1.0;
  bool recenter = false;
  std::vector<std::string> model_path;
  std::string out;
  int width = 1000, height = 0;

  worlds::WorldRequest Request(const std::string& world) const {
    worlds::WorldRequest r;
    r.world = world;
    r.seed = seed;
    r.params = ParseNameValues("--param", params);
    r.start = PointFlag("--start", start);
    r.goal = PointFlag("--goal", goal);
    r.placement = worlds::ParsePlacement(units, scale, up, recenter);
    r.model_path.assign(model_path.begin(), model_path.end());
    return r;
  }
};

// Bad input on stderr as exactly FILE:LINE: FIELD: REASON (no "error: " prefix), exit 2.
template <typename F>
void ExitTwoOnBadInput(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::fflush(stdout);
    std::fflush(stderr);
    std::exit(kExitBadInput);
  }
}

const char* kWorldHelp = "World file (.yaml), mesh (.obj .gltf .glb .dae .stl .ply .fbx) or Gazebo world (.sdf .world)";

}  // namespace

void AddPlacementOptions(CLI::App* app, std::string* units, double* scale, std::string* up, bool* recenter,
                         std::vector<std::string>* model_path) {
  std::vector<std::string> unit_names;
  for (const auto& u : worlds::kLengthUnits) unit_names.emplace_back(u.name);
  app->add_option("--units", *units, "mesh worlds: the file's length unit (default: what the file declares, else m)")
      ->check(CLI::IsMember(unit_names));
  app->add_option("--scale", *scale, "mesh worlds: uniform scale after the unit")->check(CLI::Range(1e-6, 1000.0));
  app->add_option("--up", *up, "mesh worlds: the file's up axis (default: what the file declares, else z)")
      ->check(CLI::IsMember({"y", "z"}));
  app->add_flag("--recenter", *recenter,
                "mesh worlds: move the horizontal centre of the bounds to x = y = 0 and the lowest point to z = 0");
  app->add_option("--model-path", *model_path,
                  "SDF worlds: directory of Gazebo models for model:// URIs (repeatable; then GAZEBO_MODEL_PATH)");
}

namespace {

}  // namespace

void RegisterWorldCommands(CLI::App& app) {
  CLI::App* world = app.add_subcommand("world", "Worlds: generate (seeded), validate, bird's-eye PNG, convert");
  world->require_subcommand(1);
  auto flags = std::make_shared<WorldFlags>();

  std::string ids, param_help = "Generator parameter name=value (repeatable):";
  for (const auto& g : worlds::Generators()) {
    ids += (ids.empty() ? "" : ", ") + g.id;
    param_help += "\n" + g.id + ":";
    for (const auto& p : g.params) {
      param_help += " " + p.name + " in [" + worlds::FormatFixed(p.min) + ", " + worlds::FormatFixed(p.max) +
                    "] (default " + worlds::FormatFixed(p.default_value) + ", " + p.help + ");";
    }
  }

  CLI::App* gen = world->add_subcommand("gen", "Generate a seeded world file (byte-identical for the same inputs)");
  gen->add_option("--scenario", flags->scenario, "Scenario id: " + ids)->required();
  gen->add_option("--seed", flags->seed, "Generator seed (unsigned integer)")->capture_default_str();
  gen->add_option("--param", flags->params, param_help);
  gen->add_option("--out", flags->out, "Output world file (.yaml)")->required();
  gen->callback([flags] {
    const worlds::World w = worlds::Generate(flags->scenario, flags->seed, ParseNameValues("--param", flags->params));
    worlds::SaveWorldFile(w, flags->out);
    std::printf("wrote %s: %s\n", flags->out.c_str(), Summary(w).c_str());
  });

  CLI::App* check = world->add_subcommand(
      "check", "Validate a world file (.yaml, or .obj with --start/--goal): exit 0 if valid, else 2 with "
               "FILE:LINE: FIELD: REASON on stderr");
  check->add_option("file", flags->target, kWorldHelp)->required();
  check->add_option("--start", flags->start, "Start x,y,z (overrides the file; required for mesh and SDF worlds)");
  check->add_option("--goal", flags->goal, "Goal x,y,z (overrides the file; required for mesh and SDF worlds)");
  AddPlacementOptions(check, &flags->units, &flags->scale, &flags->up, &flags->recenter, &flags->model_path);
  check->callback([flags] {
    ExitTwoOnBadInput([&] {
      const worlds::World w = worlds::ResolveWorld(flags->Request(flags->target));
      std::printf("%s: ok: %s\n", flags->target.c_str(), Summary(w).c_str());
    });
  });

  CLI::App* convert = world->add_subcommand(
      "convert", "Write any world the farm reads as its own world file (.yaml): meshes referenced with their "
                 "placement, SDF geometry as OBJ beside it");
  convert->add_option("world", flags->target, kWorldHelp)->required();
  convert->add_option("--start", flags->start, "Start x,y,z (required for mesh and SDF worlds)");
  convert->add_option("--goal", flags->goal, "Goal x,y,z (required for mesh and SDF worlds)");
  AddPlacementOptions(convert, &flags->units, &flags->scale, &flags->up, &flags->recenter, &flags->model_path);
  convert->add_option("--out", flags->out, "Output world file (.yaml)")->required();
  convert->callback([flags] {
    ExitTwoOnBadInput([&] {
      const worlds::World w = worlds::ResolveWorld(flags->Request(flags->target));
      worlds::ConvertWorld(w, std::filesystem::path(flags->target).parent_path(), flags->out);
      std::printf("wrote %s: %s\n", flags->out.c_str(), Summary(w).c_str());
    });
  });

  CLI::App* show = world->add_subcommand("show", "Draw a bird's-eye PNG of a world file or a generated scenario");
  show->add_option("world", flags->target, std::string(kWorldHelp) + ", or scenario id (" + ids + ")")->required();
  show->add_option("--seed", flags->seed, "Generator seed (scenario ids only)")->capture_default_str();
  show->add_option("--param", flags->params, param_help);
  show->add_option("--start", flags->start, "Start x,y,z (required for mesh and SDF worlds)");
  show->add_option("--goal", flags->goal, "Goal x,y,z (required for mesh and SDF worlds)");
  AddPlacementOptions(show, &flags->units, &flags->scale, &flags->up, &flags->recenter, &flags->model_path);
  show->add_option("--out", flags->out, "Output PNG")->required();
  show->add_option("--width", flags->width, "Image width in px")->check(CLI::Range(200, 8000))->capture_default_str();
  show->add_option("--height", flags->height, "Image height in px (0: from the world's aspect ratio)")
      ->check(CLI::Range(0, 8000))->capture_default_str();
  show->callback([flags] {
    const worlds::World w = worlds::ResolveWorld(flags->Request(flags->target));
    report::TopDownOptions options;
    options.width = flags->width;
    options.height = flags->height;
    const report::TopDownView view(w, options);
    view.SavePng(flags->out);
    std::printf("wrote %s: %s\n", flags->out.c_str(), Summary(w).c_str());
  });
}

}  // namespace enavi::cli
