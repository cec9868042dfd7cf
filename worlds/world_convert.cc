#include "worlds/world_convert.h"

#include <charconv>
#include <fstream>
#include <string>
#include <system_error>
#include <variant>

#include "worlds/primitives.h"
#include "worlds/world_io.h"

namespace enavi::worlds {
namespace {

// Shortest text that reads back as the same float (std::to_chars), locale-free.
std::string FloatText(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v == 0.0f ? 0.0f : v);
  return std::string(buf, r.ptr);
}

void WriteObj(const TriangleMesh& mesh, const std::filesystem::path& path) {
  std::string text = "# written by enavi world convert: metres, z up, world frame\n";
  for (const auto& v : mesh.vertices) text += "v " + FloatText(v.x()) + " " + FloatText(v.y()) + " " + FloatText(v.z()) + "\n";
  for (const auto& t : mesh.triangles) {
    text += "f " + std::to_string(t.x() + 1) + " " + std::to_string(t.y() + 1) + " " + std::to_string(t.z() + 1) + "\n";
  }
  std::filesystem::create_directories(path.parent_path());
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(text.data(), static_cast<std::streamsize>(text.size()));
  f.close();
  if (!f) throw std::runtime_error("cannot write mesh file: " + path.string());
}

// `full` relative to `root` if it lies inside it (through symlinks too), else empty.
std::filesystem::path RelativeInside(const std::filesystem::path& full, const std::filesystem::path& root) {
  std::error_code ec;
  const auto target = std::filesystem::weakly_canonical(full, ec);
  const auto base = std::filesystem::weakly_canonical(root, ec);
  if (ec) return {};
  const auto rel = target.lexically_relative(base);
  if (rel.empty() || *rel.begin() == "..") return {};
  return rel;
}

}  // namespace

void ConvertWorld(const World& world, const std::filesystem::path& source_dir, const std::filesystem::path& out) {
  const std::filesystem::path out_dir = out.parent_path().empty() ? std::filesystem::path(".") : out.parent_path();
  const std::string sidecar = out.stem().string() + "_meshes";
  World converted = world;
  // A mesh referenced by a path relative to the output, or baked into an OBJ named `stem`.
  auto convert = [&](Object& object, const std::string& stem) {
    auto* mesh = std::get_if<MeshObject>(&object);
    if (mesh == nullptr) return;
    if (!mesh->path.empty()) {
      const auto rel = RelativeInside(source_dir / mesh->path, out_dir);
      if (!rel.empty()) {
        mesh->path = rel.generic_string();
        return;
      }
    }
    // No file under the output's directory: the placed geometry itself, as an OBJ beside it.
    const std::string rel = sidecar + "/" + stem + ".obj";
    WriteObj(ObjectMesh(*mesh), out_dir / rel);
    MeshObject baked;
    baked.path = rel;
    baked.up = UpAxis::kZ;
    *mesh = baked;
  };
  for (std::size_t i = 0; i < converted.objects.size(); ++i) convert(converted.objects[i], "object" + std::to_string(i));
  // Movers' shapes are in their own frames, and so are their OBJs.
  for (std::size_t i = 0; i < converted.movers.size(); ++i) {
    auto& shape = converted.movers[i].shape;
    for (std::size_t j = 0; j < shape.size(); ++j) convert(shape[j], "mover" + std::to_string(i) + "_shape" + std::to_string(j));
  }
  SaveWorldFile(converted, out);
}

}  // namespace enavi::worlds
