#include "worlds/world_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>
#include <variant>
#include <vector>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "api/yaml_read.h"
#include "worlds/detmath.h"
#include "worlds/movers.h"
#include "worlds/number_text.h"
#include "worlds/obj_import.h"
#include "worlds/placement.h"
#include "worlds/primitives.h"

namespace enavi::worlds {
namespace {

constexpr double kMaxYaw = 6.2832;     // 2 pi, rounded up to the file precision
constexpr double kMaxRadius = 1000.0;  // m
constexpr double kMaxScale = 1000.0;
constexpr std::size_t kMaxStringLength = 256;
constexpr std::size_t kMaxMovers = 1000;
constexpr std::size_t kMaxWaypoints = 10'000;
constexpr double kMaxMoverSpeed = 50.0;  // m/s: a car in town is below 14, a person below 3
constexpr double kMaxMoverTime = 86'400.0;  // s, waypoint times and start delays

// ---------------------------------------------------------------------------------------------
// Reading

// World errors are WorldError (file, line, field, reason), raised through the shared reader.
api::YamlReader WorldReader(const std::string& file) {
  return api::YamlReader(file, [](const std::string& source, int line, const std::string& field, const std::string& reason) {
    throw WorldError(source, line, field, reason);
  });
}

struct ParseContext {
  explicit ParseContext(const std::string& file_name) : file(file_name), reader(WorldReader(file_name)) {}
  std::string file;
  api::YamlReader reader;
  std::filesystem::path base_dir;
  std::map<std::string, int> lines;  // field -> line, for errors found after parsing
  std::map<std::string, ImportedMesh> meshes;  // mesh files loaded so far, by relative path
  MeshLoader load_mesh;
  std::size_t triangles = 0;
  std::size_t max_objects = kMaxObjects;
  std::size_t max_triangles = kMaxTriangles;
};

// Counts the documents of a YAML text up to two, and where the second starts. Not
// YAML::LoadAll: yaml-cpp 0.7's parser never gets past a stray ',' where a document starts and
// LoadAll collects empty documents until memory runs out (found by world_yaml_fuzz).
class DocumentCounter : public YAML::EventHandler {
 public:
  static DocumentCounter Count(const std::string& yaml) {
    std::istringstream in(yaml);
    YAML::Parser parser(in);
    DocumentCounter counter;
    while (counter.documents_ < 2 && parser.HandleNextDocument(counter)) {
    }
    return counter;
  }
  int documents() const { return documents_; }
  int second_line() const { return second_line_; }

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ == 2) second_line_ = mark.line + 1;
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  int documents_ = 0;
  int second_line_ = 0;
};

int LineOf(const YAML::Node& node) { return api::YamlReader::Line(node); }

[[noreturn]] void Fail(const ParseContext& ctx, const YAML::Node& at, const std::string& field,
                       const std::string& reason) {
  ctx.reader.Fail(at, field, reason);
}

using api::YamlReader;
using MapView = api::YamlReader::Map;

std::string Shown(const std::string& text) { return YamlReader::Shown(text); }

std::string ReadString(const ParseContext& ctx, const YAML::Node& node, const std::string& field) {
  return ctx.reader.String(node, field, kMaxStringLength);
}

double ReadRange(const ParseContext& ctx, const YAML::Node& node, const std::string& field, double lo, double hi,
                 bool lo_open) {
  return ctx.reader.Range(node, field, lo, hi, lo_open);
}

// [x, y, z], each component checked like ReadRange; errors name the vector field.
Eigen::Vector3d ReadVec3(const ParseContext& ctx, const YAML::Node& node, const std::string& field, double lo,
                         double hi, bool lo_open) {
  if (!node.IsSequence() || node.size() != 3) {
    Fail(ctx, node, field, std::string("expected [x, y, z] (got ") +
                               (node.IsSequence() ? std::to_string(node.size()) + " values" : YamlReader::Describe(node)) + ")");
  }
  Eigen::Vector3d v;
  for (std::size_t i = 0; i < 3; ++i) v[static_cast<int>(i)] = ReadRange(ctx, node[i], field, lo, hi, lo_open);
  return v;
}

Eigen::Vector3d ReadPoint(const ParseContext& ctx, const YAML::Node& node, const std::string& field) {
  return ReadVec3(ctx, node, field, -kMaxCoordinate, kMaxCoordinate, false);
}

// A mesh path: relative, no "..", inside the world file's directory even through symlinks.
std::filesystem::path ResolveMeshPath(const ParseContext& ctx, const YAML::Node& node, const std::string& field) {
  const std::string text = ReadString(ctx, node, field);
  if (text.empty()) Fail(ctx, node, field, "empty path");
  const std::filesystem::path rel(text);
  if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory()) {
    Fail(ctx, node, field, "absolute paths are not allowed (give a path relative to the world file)");
  }
  for (const auto& part : rel) {
    if (part == "..") Fail(ctx, node, field, "'..' is not allowed (the mesh must be inside the world file's directory)");
  }
  const std::filesystem::path full = ctx.base_dir / rel;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(full, ec)) Fail(ctx, node, field, "file not found: " + full.string());
  const auto root = std::filesystem::weakly_canonical(ctx.base_dir, ec);
  const auto target = std::filesystem::weakly_canonical(full, ec);
  if (ec) Fail(ctx, node, field, "cannot resolve " + full.string() + ": " + ec.message());
  const auto [root_end, target_it] = std::mismatch(root.begin(), root.end(), target.begin(), target.end());
  if (root_end != root.end()) Fail(ctx, node, field, "resolves outside the world file's directory: " + target.string());
  return full;
}

void CountTriangles(ParseContext* ctx, const YAML::Node& at, const std::string& field, std::size_t n) {
  ctx->triangles += n;
  if (ctx->triangles > ctx->max_triangles) {
    Fail(*ctx, at, field, "the world exceeds " + std::to_string(ctx->max_triangles) + " triangles");
  }
}

Object ReadObject(ParseContext* ctx, const YAML::Node& node, const std::string& field) {
  if (!node.IsMap() || node.size() != 1) {
    Fail(*ctx, node, field, "expected one of {box: ...}, {cylinder: ...}, {ellipsoid: ...}, {mesh: ...}");
  }
  const MapView kind(ctx->reader, node, field, {"box", "cylinder", "ellipsoid", "mesh"});
  if (kind.Has("box")) {
    const MapView m(ctx->reader, kind.Get("box"), kind.Field("box"), {"center", "size", "yaw"});
    Box b;
    b.center = ReadPoint(*ctx, m.Get("center"), m.Field("center"));
    b.size = ReadVec3(*ctx, m.Get("size"), m.Field("size"), 0.0, kMaxExtent, true);
    if (m.Has("yaw")) b.yaw = ReadRange(*ctx, m.Get("yaw"), m.Field("yaw"), -kMaxYaw, kMaxYaw, false);
    CountTriangles(ctx, node, field, TriangleCount(b));
    return b;
  }
  if (kind.Has("cylinder")) {
    const MapView m(ctx->reader, kind.Get("cylinder"), kind.Field("cylinder"), {"base", "radius", "height"});
    Cylinder c;
    c.base = ReadPoint(*ctx, m.Get("base"), m.Field("base"));
    c.radius = ReadRange(*ctx, m.Get("radius"), m.Field("radius"), 0.0, kMaxRadius, true);
    c.height = ReadRange(*ctx, m.Get("height"), m.Field("height"), 0.0, kMaxExtent, true);
    CountTriangles(ctx, node, field, TriangleCount(c));
    return c;
  }
  if (kind.Has("ellipsoid")) {
    const MapView m(ctx->reader, kind.Get("ellipsoid"), kind.Field("ellipsoid"), {"center", "radii"});
    Ellipsoid e;
    e.center = ReadPoint(*ctx, m.Get("center"), m.Field("center"));
    e.radii = ReadVec3(*ctx, m.Get("radii"), m.Field("radii"), 0.0, kMaxRadius, true);
    CountTriangles(ctx, node, field, TriangleCount(e));
    return e;
  }
  const MapView m(ctx->reader, kind.Get("mesh"), kind.Field("mesh"),
                  {"file", "position", "yaw", "scale", "units", "up", "recenter"});
  const std::string path = ReadString(*ctx, m.Get("file"), m.Field("file"));
  const std::filesystem::path full = ResolveMeshPath(*ctx, m.Get("file"), m.Field("file"));
  MeshPlacement placement;
  if (m.Has("units")) {
    placement.units = ReadString(*ctx, m.Get("units"), m.Field("units"));
    if (!UnitMetres(placement.units)) {
      Fail(*ctx, m.Get("units"), m.Field("units"), "unknown unit '" + Shown(placement.units) + "' (known: " + UnitNames() + ")");
    }
  }
  if (m.Has("up")) {
    placement.up = ParseUpAxis(ReadString(*ctx, m.Get("up"), m.Field("up")));
    if (!placement.up) Fail(*ctx, m.Get("up"), m.Field("up"), "expected y or z");
  }
  if (m.Has("recenter")) {
    placement.recenter = ctx->reader.Bool(m.Get("recenter"), m.Field("recenter"));
  }
  if (m.Has("scale")) placement.scale = ReadRange(*ctx, m.Get("scale"), m.Field("scale"), 0.0, kMaxScale, true);
  auto cached = ctx->meshes.find(path);
  if (cached == ctx->meshes.end()) {
    // The error is the mesh's (its file and line), and says which world entry asked for it: the
    // user may have run `world check` on the world, not the mesh.
    try {
      cached = ctx->meshes.emplace(path, ctx->load_mesh(full)).first;
    } catch (const WorldError& e) {
      throw WorldError(e.file(), e.line(), e.field(),
                       e.reason() + " (mesh of " + ctx->file + ":" + std::to_string(LineOf(m.Get("file"))) + ": " +
                           m.Field("file") + ")");
    }
  }
  MeshObject mesh = PlaceMesh(cached->second, placement, path, full.string());
  mesh.position = ReadPoint(*ctx, m.Get("position"), m.Field("position"));
  if (m.Has("yaw")) mesh.yaw = ReadRange(*ctx, m.Get("yaw"), m.Field("yaw"), -kMaxYaw, kMaxYaw, false);
  CountTriangles(ctx, node, field, mesh.mesh.triangle_count());
  // The placed mesh must stay within the coordinate limits too.
  CheckPlacedRange(mesh, ctx->file, LineOf(node), field);
  return mesh;
}

// A mover: its shape (objects in its own frame), its waypoints at a speed or at given times.
Mover ReadMover(ParseContext* ctx, const YAML::Node& node, const std::string& field, const World& world,
                std::size_t index) {
  const MapView m(ctx->reader, node, field, {"name", "shape", "waypoints", "speed", "mode", "start_delay"});
  Mover mover;
  mover.name = m.Has("name") ? ReadString(*ctx, m.Get("name"), m.Field("name")) : "mover-" + std::to_string(index);
  if (mover.name.empty()) Fail(*ctx, m.Get("name"), m.Field("name"), "empty name");
  const YAML::Node& shape = m.Get("shape");
  if (!shape.IsSequence() || shape.size() == 0) {
    Fail(*ctx, shape, m.Field("shape"), "expected a non-empty sequence of objects in the mover's frame");
  }
  for (std::size_t i = 0; i < shape.size(); ++i) {
    mover.shape.push_back(ReadObject(ctx, shape[i], m.Field("shape") + "[" + std::to_string(i) + "]"));
  }
  if (m.Has("speed")) mover.speed = ReadRange(*ctx, m.Get("speed"), m.Field("speed"), 0.0, kMaxMoverSpeed, true);
  if (m.Has("mode")) {
    const std::string mode = ReadString(*ctx, m.Get("mode"), m.Field("mode"));
    if (!ParseMoverMode(mode, &mover.mode)) {
      Fail(*ctx, m.Get("mode"), m.Field("mode"), "unknown mode '" + Shown(mode) + "' (known: loop, back_and_forth, once)");
    }
  }
  if (m.Has("start_delay")) {
    mover.start_delay = ReadRange(*ctx, m.Get("start_delay"), m.Field("start_delay"), 0.0, kMaxMoverTime, false);
  }
  const YAML::Node& points = m.Get("waypoints");
  const std::string wfield = m.Field("waypoints");
  if (!points.IsSequence() || points.size() < 2) {
    Fail(*ctx, points, wfield, "expected a sequence of at least two waypoints");
  }
  if (points.size() > kMaxWaypoints) Fail(*ctx, points, wfield, "more than " + std::to_string(kMaxWaypoints) + " waypoints");
  double length = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string f = wfield + "[" + std::to_string(i) + "]";
    MoverWaypoint w;
    if (mover.speed > 0.0) {
      // At a speed: plain points; the heading follows the path.
      if (!points[i].IsSequence()) Fail(*ctx, points[i], f, "expected [x, y, z] (a mover with a speed has untimed waypoints)");
      w.position = ReadPoint(*ctx, points[i], f);
    } else {
      const MapView wm(ctx->reader, points[i], f, {"t", "position", "yaw"});
      w.t = ReadRange(*ctx, wm.Get("t"), wm.Field("t"), 0.0, kMaxMoverTime, false);
      w.position = ReadPoint(*ctx, wm.Get("position"), wm.Field("position"));
      if (wm.Has("yaw")) w.yaw = ReadRange(*ctx, wm.Get("yaw"), wm.Field("yaw"), -kMaxYaw, kMaxYaw, false);
      if (i > 0 && !(w.t > mover.waypoints.back().t)) {
        Fail(*ctx, wm.Get("t"), wm.Field("t"), "must be later than the waypoint before (" + FormatFixed(mover.waypoints.back().t) +
                                                   " s); without a speed, waypoints are timed");
      }
    }
    if (!world.bounds.contains(w.position)) {
      Fail(*ctx, points[i], f, "outside the bounds (a mover's path stays in the flight volume)");
    }
    if (i > 0) length += (w.position - mover.waypoints.back().position).norm();
    mover.waypoints.push_back(w);
  }
  if (mover.speed > 0.0 && !(length > 0.0)) Fail(*ctx, points, wfield, "the path has no length (every waypoint is the same point)");
  return mover;
}

World ParseDocument(ParseContext* ctx, const YAML::Node& root, const WorldFileOptions& options) {
  World world;
  const MapView top(ctx->reader, root, "",
                    {"format", "name", "metadata", "bounds", "ground", "start", "goal", "objects", "movers"});

  const std::string format = ReadString(*ctx, top.Get("format"), "format");
  if (format != kWorldFormat) {
    Fail(*ctx, top.Get("format"), "format", "unsupported format '" + Shown(format) + "' (expected " +
                                                std::string(kWorldFormat) + ")");
  }
  world.metadata.name = top.Has("name") ? ReadString(*ctx, top.Get("name"), "name")
                                        : std::filesystem::path(ctx->file).stem().string();
  world.metadata.scenario = "custom";
  if (top.Has("metadata")) {
    const MapView meta(ctx->reader, top.Get("metadata"), "metadata", {"scenario", "seed", "generator_version", "params"});
    if (meta.Has("scenario")) world.metadata.scenario = ReadString(*ctx, meta.Get("scenario"), meta.Field("scenario"));
    if (meta.Has("seed")) {
      const YAML::Node& n = meta.Get("seed");
      if (!n.IsScalar() || !ParseUint64(n.Scalar(), &world.metadata.seed)) {
        Fail(*ctx, n, meta.Field("seed"), "expected an unsigned integer");
      }
    }
    if (meta.Has("generator_version")) {
      const YAML::Node& n = meta.Get("generator_version");
      std::int64_t v = 0;
      if (!n.IsScalar() || !ParseInt64(n.Scalar(), &v) || v < 0 || v > 1'000'000) {
        Fail(*ctx, n, meta.Field("generator_version"), "expected an integer in [0, 1000000]");
      }
      world.metadata.generator_version = static_cast<int>(v);
    }
    if (meta.Has("params")) {
      const YAML::Node& params = meta.Get("params");
      if (!params.IsMap()) Fail(*ctx, params, meta.Field("params"), "expected a mapping of name: value");
      for (auto it = params.begin(); it != params.end(); ++it) {
        const std::string key = ReadString(*ctx, it->first, meta.Field("params"));
        const std::string value = ReadString(*ctx, it->second, meta.Field("params") + "." + Shown(key));
        if (!world.metadata.params.emplace(key, value).second) {
          Fail(*ctx, it->first, meta.Field("params") + "." + Shown(key), "duplicate key");
        }
      }
    }
  }

  // Bounds: min < max per axis, at most kMaxExtent.
  {
    const MapView b(ctx->reader, top.Get("bounds"), "bounds", {"min", "max"});
    const Eigen::Vector3d lo = ReadPoint(*ctx, b.Get("min"), "bounds.min");
    const Eigen::Vector3d hi = ReadPoint(*ctx, b.Get("max"), "bounds.max");
    for (int a = 0; a < 3; ++a) {
      if (!(hi[a] > lo[a])) {
        Fail(*ctx, b.Get("max"), "bounds.max", std::string("must exceed bounds.min along ") + "xyz"[a] + " (got " +
                                                   FormatFixed(hi[a]) + " <= " + FormatFixed(lo[a]) + ")");
      }
      if (hi[a] - lo[a] > kMaxExtent) {
        Fail(*ctx, top.Get("bounds"), "bounds", std::string("extent along ") + "xyz"[a] + " is " +
                                                    FormatFixed(hi[a] - lo[a]) + " m (limit 2000 m)");
      }
    }
    world.bounds = Eigen::AlignedBox3d(lo, hi);
    ctx->lines["bounds"] = top.KeyLine("bounds");
  }

  if (top.Has("ground")) {
    const YAML::Node& g = top.Get("ground");
    if (g.IsScalar() && g.Scalar() == "none") {
      world.ground.enabled = false;
    } else if (g.IsMap()) {
      const MapView gm(ctx->reader, g, "ground", {"z"});
      world.ground.enabled = true;
      world.ground.z = ReadRange(*ctx, gm.Get("z"), "ground.z", -kMaxCoordinate, kMaxCoordinate, false);
    } else {
      Fail(*ctx, g, "ground", "expected {z: number} or none");
    }
  }

  // Start and goal; a command-line override makes the file's value optional.
  const std::pair<const char*, const std::optional<Eigen::Vector3d>*> ends[2] = {{"start", &options.start},
                                                                                 {"goal", &options.goal}};
  for (const auto& [name, override_value] : ends) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    if (top.Has(name) || !override_value->has_value()) {
      p = ReadPoint(*ctx, top.Get(name), name);
      ctx->lines[name] = top.KeyLine(name);
    }
    if (override_value->has_value()) {
      p = **override_value;
      ctx->lines[name] = 0;  // the error is about the command line, not the file
    }
    (std::string(name) == "start" ? world.start : world.goal) = p;
  }

  if (top.Has("objects")) {
    const YAML::Node& objects = top.Get("objects");
    if (!objects.IsSequence()) {
      Fail(*ctx, objects, "objects", std::string("expected a sequence (got ") + YamlReader::Describe(objects) + ")");
    }
    if (objects.size() > ctx->max_objects) {
      Fail(*ctx, objects, "objects", "more than " + std::to_string(ctx->max_objects) + " objects (" +
                                         std::to_string(objects.size()) + ")");
    }
    world.objects.reserve(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string field = "objects[" + std::to_string(i) + "]";
      world.objects.push_back(ReadObject(ctx, objects[i], field));
      ctx->lines[field] = LineOf(objects[i]);
    }
  }

  if (top.Has("movers")) {
    const YAML::Node& movers = top.Get("movers");
    if (!movers.IsSequence()) {
      Fail(*ctx, movers, "movers", std::string("expected a sequence (got ") + YamlReader::Describe(movers) + ")");
    }
    if (movers.size() > kMaxMovers) Fail(*ctx, movers, "movers", "more than " + std::to_string(kMaxMovers) + " movers");
    std::set<std::string> names;
    for (std::size_t i = 0; i < movers.size(); ++i) {
      const std::string field = "movers[" + std::to_string(i) + "]";
      world.movers.push_back(ReadMover(ctx, movers[i], field, world, i));
      if (!names.insert(world.movers.back().name).second) {
        Fail(*ctx, movers[i], field + ".name", "duplicate name '" + Shown(world.movers.back().name) + "'");
      }
      ctx->lines[field] = LineOf(movers[i]);
    }
  }
  return world;
}

// ---------------------------------------------------------------------------------------------
// Writing

std::string Num(double v) { return FormatFixed(detmath::Quantize(v), kWorldFileDecimals); }

std::string Vec(const Eigen::Vector3d& v) { return "[" + Num(v.x()) + ", " + Num(v.y()) + ", " + Num(v.z()) + "]"; }

using api::YamlQuoted;

std::string Key(const std::string& s) {
  const bool plain = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
  return plain ? s : YamlQuoted(s);
}

}  // namespace

World ParseWorld(std::string_view yaml, const std::string& file_name, const std::filesystem::path& base_dir,
                 const WorldFileOptions& options) {
  ParseContext ctx(file_name);
  ctx.base_dir = base_dir.empty() ? std::filesystem::path(".") : base_dir;
  ctx.max_objects = options.max_objects;
  ctx.max_triangles = options.max_triangles;
  ctx.load_mesh = options.load_mesh ? options.load_mesh : [](const std::filesystem::path& p) {
    if (p.extension() != ".obj") {
      throw WorldError(p.string(), 0, "file", "only .obj meshes can be read here (other formats need enavi::world_import)");
    }
    return LoadObjFile(p);
  };
  World world;
  try {
    const std::string text(yaml);
    const DocumentCounter docs = DocumentCounter::Count(text);
    if (docs.documents() == 0) throw WorldError(file_name, 0, "document", "empty file (expected a world mapping)");
    if (docs.documents() > 1) throw WorldError(file_name, docs.second_line(), "document", "more than one YAML document");
    world = ParseDocument(&ctx, ctx.reader.Load(text), options);
  } catch (const YAML::Exception& e) {
    // yaml-cpp may still throw while a document is walked (a bad node deep in it).
    throw WorldError(file_name, e.mark.line >= 0 ? e.mark.line + 1 : 0, "yaml", e.msg);
  }
  if (options.validate) {
    const ValidationResult v = ValidateWorld(world, options.validation);
    if (!v.ok) {
      const auto it = ctx.lines.find(v.field);
      throw WorldError(file_name, it == ctx.lines.end() ? 0 : it->second, v.field, v.reason);
    }
  }
  return world;
}

World LoadWorldFile(const std::filesystem::path& path, const WorldFileOptions& options) {
  return ParseWorld(ReadInputFile(path), path.string(), path.parent_path(), options);
}

std::string WorldToYaml(const World& world) {
  std::string out;
  out += "format: " + std::string(kWorldFormat) + "\n";
  out += "name: " + YamlQuoted(world.metadata.name) + "\n";
  out += "metadata:\n";
  out += "  scenario: " + YamlQuoted(world.metadata.scenario) + "\n";
  out += "  seed: " + std::to_string(world.metadata.seed) + "\n";
  out += "  generator_version: " + std::to_string(world.metadata.generator_version) + "\n";
  out += "  params: {";
  bool first = true;
  for (const auto& [k, v] : world.metadata.params) {
    out += (first ? "" : ", ") + Key(k) + ": " + YamlQuoted(v);
    first = false;
  }
  out += "}\n";
  out += "bounds: {min: " + Vec(world.bounds.min()) + ", max: " + Vec(world.bounds.max()) + "}\n";
  out += world.ground.enabled ? "ground: {z: " + Num(world.ground.z) + "}\n" : "ground: none\n";
  out += "start: " + Vec(world.start) + "\n";
  out += "goal: " + Vec(world.goal) + "\n";
  out += world.objects.empty() ? "objects: []\n" : "objects:\n";
  struct Writer {
    std::string* out;
    std::string indent = "  ";
    void operator()(const Box& b) const {
      *out += indent + "- box: {center: " + Vec(b.center) + ", size: " + Vec(b.size) + ", yaw: " + Num(b.yaw) + "}\n";
    }
    void operator()(const Cylinder& c) const {
      *out += indent + "- cylinder: {base: " + Vec(c.base) + ", radius: " + Num(c.radius) + ", height: " + Num(c.height) + "}\n";
    }
    void operator()(const Ellipsoid& e) const {
      *out += indent + "- ellipsoid: {center: " + Vec(e.center) + ", radii: " + Vec(e.radii) + "}\n";
    }
    void operator()(const MeshObject& m) const {
      if (m.path.empty()) {
        throw std::invalid_argument("a mesh with no file of its own (imported from SDF) cannot be written to a "
                                    "world file; `enavi world convert` writes it as an OBJ first");
      }
      *out += indent + "- mesh: {file: " + YamlQuoted(m.path) + ", position: " + Vec(m.position) + ", yaw: " + Num(m.yaw) +
              ", scale: " + Num(m.scale);
      if (!m.units.empty()) *out += ", units: " + YamlQuoted(m.units);
      if (m.up) *out += std::string(", up: ") + YamlQuoted(UpAxisName(*m.up));
      if (m.recenter) *out += ", recenter: true";
      *out += "}\n";
    }
  };
  for (const auto& o : world.objects) std::visit(Writer{&out}, o);
  if (world.movers.empty()) return out;
  out += "movers:\n";
  for (const Mover& m : world.movers) {
    out += "  - name: " + YamlQuoted(m.name) + "\n";
    out += std::string("    mode: ") + YamlQuoted(MoverModeName(m.mode)) + "\n";
    if (m.speed > 0.0) out += "    speed: " + Num(m.speed) + "\n";
    out += "    start_delay: " + Num(m.start_delay) + "\n";
    out += "    shape:\n";
    for (const auto& o : m.shape) std::visit(Writer{&out, "      "}, o);
    out += "    waypoints:\n";
    for (const MoverWaypoint& w : m.waypoints) {
      out += m.speed > 0.0 ? "      - " + Vec(w.position) + "\n"
                           : "      - {t: " + Num(w.t) + ", position: " + Vec(w.position) + ", yaw: " + Num(w.yaw) + "}\n";
    }
  }
  return out;
}

void SaveWorldFile(const World& world, const std::filesystem::path& path) {
  const std::string text = WorldToYaml(world);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error("cannot open world file for writing: " + path.string());
  f.write(text.data(), static_cast<std::streamsize>(text.size()));
  f.close();
  if (!f) throw std::runtime_error("cannot write world file: " + path.string());
}

}  // namespace enavi::worlds
