#include "api/job_spec.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "api/yaml_read.h"

namespace enavi::api {
namespace {

namespace fs = std::filesystem;

// Error reporting: every message reads FILE:LINE: field: reason (the shared YAML reader's, as
// JobSpecError; a node without a position is blamed on line 1).
class Context {
 public:
  Context(std::string file, const JobSpecOptions& options)
      : reader_(std::move(file),
                [](const std::string& source, int line, const std::string& field, const std::string& reason) {
                  throw JobSpecError(source, line > 0 ? line : 1, field, reason);
                }),
        catalog_(options.catalog) {
    std::vector<fs::path> roots = options.allowed_roots;
    if (roots.empty()) roots.push_back(fs::current_path());
    for (const auto& r : roots) roots_.push_back(fs::weakly_canonical(fs::absolute(r)));
  }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& field, const std::string& reason) const {
    reader_.Fail(at, field, reason);
  }

  const YamlReader& reader() const { return reader_; }
  const std::vector<fs::path>& roots() const { return roots_; }
  const Catalog& catalog() const { return catalog_; }
  /// The job's ROS methods (ros_methods:), known before `methods` is read.
  std::vector<std::string>& ros_methods() const { return ros_methods_; }
  bool IsRosMethod(const std::string& m) const {
    return std::find(ros_methods_.begin(), ros_methods_.end(), m) != ros_methods_.end();
  }

 private:
  YamlReader reader_;
  const Catalog& catalog_;
  mutable std::vector<std::string> ros_methods_;
  std::vector<fs::path> roots_;
};

std::string Join(const auto& items) {
  std::string out;
  for (const auto& i : items) {
    if (!out.empty()) out += ", ";
    out += i;
  }
  return out;
}

std::vector<std::string> MethodNames(const Context& ctx) {
  std::vector<std::string> names;
  for (const MethodEntry& m : ctx.catalog().methods) names.push_back(m.name);
  names.insert(names.end(), ctx.ros_methods().begin(), ctx.ros_methods().end());
  return names;
}

std::vector<std::string> RegisteredMethodNames(const Context& ctx) {
  std::vector<std::string> names;
  for (const MethodEntry& m : ctx.catalog().methods) names.push_back(m.name);
  return names;
}

std::string Format(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

template <typename List>
bool Contains(const List& list, const std::string& value) {
  return std::find_if(std::begin(list), std::end(list),
                      [&](const auto& x) { return value == x; }) != std::end(list);
}

std::string Scalar(const Context& ctx, const YAML::Node& n, const std::string& field) {
  return ctx.reader().Scalar(n, field);
}

std::int64_t Integer(const Context& ctx, const YAML::Node& n, const std::string& field) {
  return ctx.reader().Integer(n, field);
}

double Number(const Context& ctx, const YAML::Node& n, const std::string& field, double lo, double hi) {
  return ctx.reader().Range(n, field, lo, hi);
}

// A dilation: wall seconds per sim second, or `auto` (kAutoDilation).
double Dilation(const Context& ctx, const YAML::Node& n, const std::string& field) {
  if (n.IsScalar()) {
    if (n.Scalar() == "auto") return kAutoDilation;
    double v = 0;
    if (!YAML::convert<double>::decode(n, v))
      ctx.Fail(n, field, "expected wall seconds per sim second in [0.01, 100] or auto (got " + n.Scalar() + ")");
  }
  return Number(ctx, n, field, 0.01, kMaxDilation);
}

std::vector<YAML::Node> Items(const Context& ctx, const YAML::Node& n, const std::string& field) {
  return ctx.reader().Items(n, field);
}

void CheckKeys(const Context& ctx, const YAML::Node& map, const std::string& where,
               std::initializer_list<const char*> allowed) {
  ctx.reader().CheckKeys(map, where, allowed);
}

bool Bool(const Context& ctx, const YAML::Node& n, const std::string& field) { return ctx.reader().Bool(n, field); }

std::vector<std::string> Choices(const Context& ctx, const YAML::Node& n, const std::string& field,
                                 const auto& known, const char* what) {
  std::vector<std::string> out;
  const auto items = Items(ctx, n, field);
  if (items.empty()) ctx.Fail(n, field, "empty list");
  for (const auto& item : items) {
    const std::string v = Scalar(ctx, item, field);
    if (!Contains(known, v)) {
      ctx.Fail(item, field,
               std::string("unknown ") + what + " '" + v + "' (known: " + Join(known) + ")");
    }
    if (Contains(out, v)) ctx.Fail(item, field, "'" + v + "' listed twice");
    out.push_back(v);
  }
  return out;
}

// Resolves a file named in the spec against the allowed roots; returns its canonical path.
// With `directory`, names a directory instead (any extension).
std::string ResolveFile(const Context& ctx, const YAML::Node& n, const std::string& field,
                        const std::string& value, std::initializer_list<const char*> extensions,
                        bool directory = false) {
  const fs::path given(value);
  const std::string ext = given.extension().string();
  if (!directory && !Contains(extensions, ext)) {
    ctx.Fail(n, field,
             "'" + value + "' has extension '" + ext + "', expected one of " +
                 Join(extensions));
  }
  const fs::path resolved =
      fs::weakly_canonical(given.is_absolute() ? given : ctx.roots().front() / given);
  const bool inside = std::any_of(ctx.roots().begin(), ctx.roots().end(), [&](const fs::path& r) {
    const auto rel = resolved.lexically_relative(r);
    return !rel.empty() && *rel.begin() != "..";
  });
  if (!inside) {
    std::vector<std::string> roots;
    for (const auto& r : ctx.roots()) roots.push_back(r.string());
    ctx.Fail(n, field, "'" + value + "' is outside the allowed roots (" + Join(roots) + ")");
  }
  if (directory ? !fs::is_directory(resolved) : !fs::is_regular_file(resolved)) {
    ctx.Fail(n, field, "'" + value + (directory ? "': no such directory" : "': no such file"));
  }
  return resolved.string();
}

// A policy by content hash, or a file under the allowed roots.
std::string Policy(const Context& ctx, const YAML::Node& n, const std::string& field) {
  const std::string value = Scalar(ctx, n, field);
  if (value.rfind(kPolicyHashPrefix, 0) == 0) {
    if (!IsPolicyHashRef(value)) ctx.Fail(n, field, "expected sha256: and 64 lower-case hex digits");
    return value;
  }
  return ResolveFile(ctx, n, field, value, {".json", ".bin", ".pt"});
}

Vec3 Point(const Context& ctx, const YAML::Node& n, const std::string& field) {
  if (!n.IsSequence() || n.size() != 3) ctx.Fail(n, field, "expected [x, y, z]");
  Vec3 p;
  for (std::size_t i = 0; i < 3; ++i) p[i] = Number(ctx, n[i], field, -1e5, 1e5);
  return p;
}

std::map<std::string, std::string> StringMap(const Context& ctx, const YAML::Node& n,
                                             const std::string& field) {
  if (!n.IsMap()) ctx.Fail(n, field, "expected a map of name: value");
  std::map<std::string, std::string> out;
  for (const auto& kv : n) {
    const std::string key = Scalar(ctx, kv.first, field);
    if (!out.emplace(key, Scalar(ctx, kv.second, field + "." + key)).second) {
      ctx.Fail(kv.first, field + "." + key, "duplicate key");
    }
  }
  return out;
}

// Tunable names: lower-case identifiers (the runner validates names and ranges).
// An override must be a tunable of every method it applies to, inside that tunable's range.
void CheckTunable(const Context& ctx, const YAML::Node& at, const std::string& field, const std::string& key,
                  double value, const std::vector<std::string>& methods) {
  for (const std::string& prefix : ctx.catalog().unchecked_prefixes)
    if (key.rfind(prefix, 0) == 0) return;
  for (const std::string& method : methods) {
    if (ctx.IsRosMethod(method))
      ctx.Fail(at, field + "." + key,
               "method " + method + " is a ROS stack: it has no tunables (its launch arguments are ros_methods." +
                   method + ".args)");
    const MethodEntry* m = ctx.catalog().Find(method);
    if (!m) continue;  // reported where the method was named
    const auto t = std::find_if(m->tunables.begin(), m->tunables.end(),
                                [&](const TunableRange& r) { return r.name == key; });
    if (t == m->tunables.end()) {
      std::vector<std::string> names;
      for (const TunableRange& r : m->tunables) names.push_back(r.name);
      ctx.Fail(at, field + "." + key, "not a tunable of method " + method + " (known: " + Join(names) + ")");
    }
    if (value < t->min || value > t->max || (t->integer && value != std::floor(value))) {
      std::ostringstream range;
      range << "[" << t->min << ", " << t->max << "]";
      ctx.Fail(at, field + "." + key,
               "method " + method + ": " + Format(value) + " is outside " + range.str() + (t->integer ? " or not an integer" : ""));
    }
  }
}

std::map<std::string, double> Tunables(const Context& ctx, const YAML::Node& n,
                                       const std::string& field, const std::vector<std::string>& methods) {
  if (!n.IsMap()) ctx.Fail(n, field, "expected a map of tunable: number");
  std::map<std::string, double> out;
  for (const auto& kv : n) {
    const std::string key = Scalar(ctx, kv.first, field);
    const bool ok = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
      return std::islower(static_cast<unsigned char>(c)) ||
             std::isdigit(static_cast<unsigned char>(c)) || c == '_' || c == '.';
    });
    if (!ok) ctx.Fail(kv.first, field + "." + key, "tunable names are lower_case identifiers");
    const double value = Number(ctx, kv.second, field + "." + key, -1e12, 1e12);
    if (!out.emplace(key, value).second) ctx.Fail(kv.first, field + "." + key, "duplicate key");
    CheckTunable(ctx, kv.second, field, key, value, methods);
  }
  return out;
}

// World files a scenario may name: the farm's own, the mesh formats of worlds::kMeshFormats
// and Gazebo SDF (tests/unit/worlds/import_test.cc checks that every mesh format and unit is accepted).
constexpr std::initializer_list<const char*> kWorldFileExtensions = {
    ".yaml", ".yml", ".obj", ".gltf", ".glb", ".dae", ".stl", ".ply", ".fbx", ".sdf", ".world"};
// Mesh placement units (worlds::kLengthUnits) and up axes.
constexpr std::array<const char*, 5> kUnits = {"m", "cm", "mm", "in", "ft"};
constexpr std::array<const char*, 2> kUpAxes = {"y", "z"};

std::map<std::string, std::string> Labels(const Context& ctx, const YAML::Node& n) {
  std::map<std::string, std::string> labels = StringMap(ctx, n, "labels");
  if (labels.size() > kMaxLabels) {
    ctx.Fail(n, "labels", std::to_string(labels.size()) + " labels, at most " +
                              std::to_string(kMaxLabels));
  }
  for (const auto& kv : n) {
    const std::string key = kv.first.as<std::string>();
    const std::string error = LabelError(key, labels.at(key));
    if (!error.empty()) ctx.Fail(kv.first, "labels." + key, error);
  }
  return labels;
}

ScenarioEntry Scenario(const Context& ctx, const YAML::Node& n) {
  ScenarioEntry entry;
  if (n.IsMap()) {
    CheckKeys(ctx, n, "scenarios",
              {"world", "start", "goal", "params", "units", "scale", "up", "recenter", "model_path"});
    if (!n["world"]) ctx.Fail(n, "scenarios.world", "missing");
    if (n["start"]) entry.start = Point(ctx, n["start"], "scenarios.start");
    if (n["goal"]) entry.goal = Point(ctx, n["goal"], "scenarios.goal");
    if (n["params"]) entry.params = StringMap(ctx, n["params"], "scenarios.params");
    if (n["units"]) {
      entry.units = Scalar(ctx, n["units"], "scenarios.units");
      if (!Contains(kUnits, entry.units))
        ctx.Fail(n["units"], "scenarios.units", "unknown unit '" + entry.units + "' (known: " + Join(kUnits) + ")");
    }
    if (n["scale"]) entry.scale = Number(ctx, n["scale"], "scenarios.scale", 1e-6, 1000.0);
    if (n["up"]) {
      entry.up = Scalar(ctx, n["up"], "scenarios.up");
      if (!Contains(kUpAxes, entry.up)) ctx.Fail(n["up"], "scenarios.up", "expected y or z (got '" + entry.up + "')");
    }
    if (n["recenter"]) entry.recenter = Bool(ctx, n["recenter"], "scenarios.recenter");
    if (n["model_path"]) {
      for (const auto& item : Items(ctx, n["model_path"], "scenarios.model_path")) {
        entry.model_path.push_back(
            ResolveFile(ctx, item, "scenarios.model_path", Scalar(ctx, item, "scenarios.model_path"), {}, true));
      }
    }
  } else if (!n.IsScalar()) {
    ctx.Fail(n, "scenarios", "expected a scenario id, a world file or {world: ...}");
  }
  // Never assign YAML::Node to an existing node: yaml-cpp would overwrite the node it refers to.
  const YAML::Node world_node = n.IsMap() ? n["world"] : n;
  const std::string world = Scalar(ctx, world_node, "scenarios");
  if (Contains(ctx.catalog().scenarios, world)) {
    entry.world = world;
  } else if (world.find('/') != std::string::npos || world.find('.') != std::string::npos) {
    entry.world = ResolveFile(ctx, world_node, "scenarios", world, kWorldFileExtensions);
    const std::string ext = fs::path(world).extension().string();
    const bool own = ext == ".yaml" || ext == ".yml";
    if (!own && (!entry.start || !entry.goal)) {
      ctx.Fail(world_node, "scenarios", "'" + world + "' is a mesh or SDF world: give start and goal");
    }
    if (own && (!entry.units.empty() || entry.scale != 1.0 || !entry.up.empty() || entry.recenter)) {
      ctx.Fail(world_node, "scenarios", "units, scale, up and recenter apply to mesh files (a world file places its meshes)");
    }
  } else {
    ctx.Fail(world_node, "scenarios",
             "unknown scenario '" + world + "' (known: " + Join(ctx.catalog().scenarios) +
                 ", or a world file: " + Join(kWorldFileExtensions) + ")");
  }
  return entry;
}

std::vector<std::uint64_t> Seeds(const Context& ctx, const YAML::Node& n) {
  std::vector<std::uint64_t> seeds;
  if (n.IsScalar()) {
    const std::int64_t count = Integer(ctx, n, "seeds");
    if (count < 1 || count > kMaxSeedCount) {
      ctx.Fail(n, "seeds",
               "count " + std::to_string(count) + " outside [1, " +
                   std::to_string(kMaxSeedCount) + "]");
    }
    for (std::int64_t s = 1; s <= count; ++s) seeds.push_back(static_cast<std::uint64_t>(s));
    return seeds;
  }
  if (!n.IsSequence() || n.size() == 0) ctx.Fail(n, "seeds", "expected a count or a list of seeds");
  if (n.size() > static_cast<std::size_t>(kMaxSeedCount)) {
    ctx.Fail(n, "seeds",
             std::to_string(n.size()) + " seeds above the limit " + std::to_string(kMaxSeedCount));
  }
  for (const auto& item : n) {
    const std::int64_t s = Integer(ctx, item, "seeds");
    if (s < 0 || s > (std::int64_t{1} << 53)) {
      ctx.Fail(item, "seeds", "seed " + std::to_string(s) + " outside [0, 2^53]");
    }
    if (std::find(seeds.begin(), seeds.end(), static_cast<std::uint64_t>(s)) != seeds.end()) ctx.Fail(item, "seeds", "seed " + std::to_string(s) + " listed twice");
    seeds.push_back(static_cast<std::uint64_t>(s));
  }
  return seeds;
}

EpisodeOverride Override(const Context& ctx, const YAML::Node& n, std::size_t index,
                         const std::vector<std::string>& job_methods) {
  const std::string f = "episode_overrides[" + std::to_string(index) + "]";
  if (!n.IsMap()) ctx.Fail(n, f, "expected a map with match: and settings");
  CheckKeys(ctx, n, f, {"match", "timeout_s", "dilation", "policy", "overrides", "world_params"});
  EpisodeOverride o;
  if (const YAML::Node m = n["match"]) {
    if (!m.IsMap()) ctx.Fail(m, f + ".match", "expected a map of board/scenario/method/seed");
    CheckKeys(ctx, m, f + ".match", {"board", "scenario", "method", "seed"});
    if (m["board"]) o.boards = Choices(ctx, m["board"], f + ".match.board", ctx.catalog().boards, "board");
    if (m["method"]) o.methods = Choices(ctx, m["method"], f + ".match.method", MethodNames(ctx), "method");
    if (m["scenario"]) {
      for (const auto& item : Items(ctx, m["scenario"], f + ".match.scenario")) {
        o.scenarios.push_back(Scenario(ctx, item).world);
      }
    }
    if (m["seed"]) {
      for (const auto& item : Items(ctx, m["seed"], f + ".match.seed")) {
        const std::int64_t s = Integer(ctx, item, f + ".match.seed");
        if (s < 0) ctx.Fail(item, f + ".match.seed", "negative seed");
        o.seeds.push_back(static_cast<std::uint64_t>(s));
      }
    }
  }
  if (n["timeout_s"]) o.timeout_s = Number(ctx, n["timeout_s"], f + ".timeout_s", 0, kMaxTimeoutS);
  if (n["dilation"]) o.dilation = Dilation(ctx, n["dilation"], f + ".dilation");
  if (n["policy"]) {
    o.policy = Policy(ctx, n["policy"], f + ".policy");
  }
  if (n["overrides"]) o.overrides = Tunables(ctx, n["overrides"], f + ".overrides", o.methods.empty() ? job_methods : o.methods);
  if (n["world_params"]) o.world_params = StringMap(ctx, n["world_params"], f + ".world_params");
  return o;
}

EpisodePick Pick(const Context& ctx, const YAML::Node& n) {
  const std::string f = "episodes";
  if (!n.IsMap()) ctx.Fail(n, f, "expected {board: B, scenario: S, seed: N}");
  CheckKeys(ctx, n, f, {"board", "scenario", "seed"});
  for (const char* required : {"board", "scenario", "seed"}) {
    if (!n[required]) ctx.Fail(n, f + "." + required, "missing (required)");
  }
  EpisodePick p;
  p.board = Choices(ctx, n["board"], f + ".board", ctx.catalog().boards, "board").front();
  p.scenario = Scenario(ctx, n["scenario"]);
  const std::int64_t seed = Integer(ctx, n["seed"], f + ".seed");
  if (seed < 0 || seed > (std::int64_t{1} << 53)) {
    ctx.Fail(n["seed"], f + ".seed", "seed " + std::to_string(seed) + " outside [0, 2^53]");
  }
  p.seed = static_cast<std::uint64_t>(seed);
  return p;
}

bool Matches(const EpisodeOverride& o, const EpisodeSpec& e) {
  auto in = [](const auto& list, const auto& v) {
    return list.empty() || std::find(list.begin(), list.end(), v) != list.end();
  };
  return in(o.boards, e.board) && in(o.scenarios, e.world) && in(o.methods, e.method) &&
         in(o.seeds, e.seed);
}

// ros_methods: name -> a stack file under the allowed roots (its errors name that file) or the
// stack inline (they name the job spec).
// The air of every episode of the job (api::WindSpec); the ranges are WindSpecError's.
WindSpec Wind(const Context& ctx, const YAML::Node& n) {
  if (!n.IsMap()) ctx.Fail(n, "wind", "expected a map of speed_mps, direction_deg, turbulence, gust");
  CheckKeys(ctx, n, "wind", {"speed_mps", "direction_deg", "turbulence", "gust"});
  WindSpec w;
  if (n["speed_mps"]) w.speed_mps = Number(ctx, n["speed_mps"], "wind.speed_mps", 0, kMaxWindSpeed);
  if (n["direction_deg"]) w.direction_deg = Number(ctx, n["direction_deg"], "wind.direction_deg", -360, 360);
  if (n["turbulence"])
    w.turbulence = Choices(ctx, n["turbulence"], "wind.turbulence", kTurbulenceLevels, "turbulence level").front();
  if (const YAML::Node g = n["gust"]) {
    if (!g.IsMap()) ctx.Fail(g, "wind.gust", "expected a map of speed_mps, direction_deg, start_s, rise_s, hold_s");
    CheckKeys(ctx, g, "wind.gust", {"speed_mps", "direction_deg", "start_s", "rise_s", "hold_s"});
    if (g["speed_mps"]) w.gust.speed_mps = Number(ctx, g["speed_mps"], "wind.gust.speed_mps", 0, kMaxWindSpeed);
    if (g["direction_deg"]) w.gust.direction_deg = Number(ctx, g["direction_deg"], "wind.gust.direction_deg", -360, 360);
    if (g["start_s"]) w.gust.start_s = Number(ctx, g["start_s"], "wind.gust.start_s", 0, kMaxTimeoutS);
    if (g["rise_s"]) w.gust.rise_s = Number(ctx, g["rise_s"], "wind.gust.rise_s", 0.01, kMaxTimeoutS);
    if (g["hold_s"]) w.gust.hold_s = Number(ctx, g["hold_s"], "wind.gust.hold_s", 0, kMaxTimeoutS);
  }
  return w;
}

std::map<std::string, RosStack> RosMethods(const Context& ctx, const YAML::Node& n) {
  if (!n.IsMap() || n.size() == 0) ctx.Fail(n, "ros_methods", "expected a map of method name: stack file or stack");
  CheckKeys(ctx, n, "ros_methods", {});
  std::map<std::string, RosStack> out;
  const std::vector<std::string> reserved = RegisteredMethodNames(ctx);
  for (const auto& kv : n) {
    const std::string name = Scalar(ctx, kv.first, "ros_methods");
    const std::string field = "ros_methods." + name;
    RosStack stack;
    if (kv.second.IsScalar()) {
      const std::string file = ResolveFile(ctx, kv.second, field, Scalar(ctx, kv.second, field), {".yaml", ".yml"});
      try {
        stack = LoadRosStack(file, reserved);
      } catch (const RosStackError& e) {
        throw JobSpecError(e.what());
      }
      // The job's key names the method, whatever the file calls it.
      stack.name = name;
      if (std::find(reserved.begin(), reserved.end(), name) != reserved.end())
        ctx.Fail(kv.first, field, "'" + name + "' is a registered method's name");
    } else {
      YamlReader::Thrower thrower = [](const std::string& source, int line, const std::string& f, const std::string& reason) {
        throw JobSpecError(source, line > 0 ? line : 1, f, reason);
      };
      const YamlReader nested(ctx.reader().source(), [field, thrower](const std::string& source, int line,
                                                                      const std::string& f, const std::string& reason) {
        thrower(source, line, YamlReader::Join(field, f), reason);
      });
      stack = ParseRosStack(nested, kv.second, ctx.roots().front().string(), name, reserved);
    }
    out.emplace(name, std::move(stack));
    ctx.ros_methods().push_back(name);
  }
  return out;
}

}  // namespace

JobSpec ParseJobSpec(const std::string& yaml_text, const std::string& file_name,
                     const JobSpecOptions& options) {
  const Catalog& c = options.catalog;
  if (c.methods.empty() || c.boards.empty() || c.scenarios.empty() || c.clocks.empty())
    throw std::logic_error("ParseJobSpec: incomplete catalog (the composition root passes the registries')");
  const Context ctx(file_name, options);
  const YAML::Node loaded = ctx.reader().Load(yaml_text);
  // const: operator[] on a mutable node would insert the keys it looks up.
  const YAML::Node root = loaded;
  if (!root.IsMap()) ctx.Fail(root, "job", "expected a YAML map of name, boards, scenarios, ...");
  CheckKeys(ctx, root, "",
            {"name", "boards", "scenarios", "methods", "seeds", "clock", "cost", "dilation", "speed_probe",
             "timeout_s", "policy", "world_params", "overrides", "episode_overrides", "episodes",
             "collect", "sample", "labels", "ros_methods", "rosbag", "wind", "odometry_noise"});
  // Either the matrix or an explicit episode list.
  if (root["episodes"]) {
    for (const char* matrix : {"boards", "scenarios", "seeds"}) {
      if (root[matrix]) ctx.Fail(root[matrix], matrix, "not with episodes: (give one or the other)");
    }
    if (!root["methods"]) ctx.Fail(root, "methods", "missing (required)");
  } else {
    for (const char* required : {"boards", "scenarios", "methods", "seeds"}) {
      if (!root[required]) ctx.Fail(root, required, "missing (required)");
    }
  }

  JobSpec job;
  if (root["name"]) {
    job.name = Scalar(ctx, root["name"], "name");
    if (job.name.empty() || job.name.size() > 128) ctx.Fail(root["name"], "name", "1..128 characters");
  } else {
    job.name = fs::path(file_name).stem().string();
  }
  if (root["ros_methods"]) job.ros_methods = RosMethods(ctx, root["ros_methods"]);
  job.methods = Choices(ctx, root["methods"], "methods", MethodNames(ctx), "method");
  if (const YAML::Node list = root["episodes"]) {
    if (!list.IsSequence() || list.size() == 0) ctx.Fail(list, "episodes", "expected a non-empty list");
    if (list.size() > options.max_episodes) {
      ctx.Fail(list, "episodes",
               std::to_string(list.size()) + " episodes, above the limit " +
                   std::to_string(options.max_episodes));
    }
    for (const auto& item : list) job.episodes.push_back(Pick(ctx, item));
  } else {
    job.boards = Choices(ctx, root["boards"], "boards", ctx.catalog().boards, "board");
    for (const auto& item : Items(ctx, root["scenarios"], "scenarios")) {
      ScenarioEntry entry = Scenario(ctx, item);
      for (const auto& other : job.scenarios) {
        if (other.world == entry.world) ctx.Fail(item, "scenarios", "'" + entry.world + "' listed twice");
      }
      job.scenarios.push_back(std::move(entry));
    }
    if (job.scenarios.empty()) ctx.Fail(root["scenarios"], "scenarios", "empty list");
    job.seeds = Seeds(ctx, root["seeds"]);
  }
  if (root["clock"]) job.clock = Choices(ctx, root["clock"], "clock", ctx.catalog().clocks, "clock").front();
  if (root["cost"]) job.cost = Choices(ctx, root["cost"], "cost", kCostModes, "cost mode").front();
  if (root["dilation"]) job.dilation = Dilation(ctx, root["dilation"], "dilation");
  if (const YAML::Node probe = root["speed_probe"]) {
    job.speed_probe = Choices(ctx, probe, "speed_probe", kSpeedProbeModes, "speed probe mode").front();
    if (job.clock != "emulated")
      ctx.Fail(probe, "speed_probe", "the emulated clock's (this job's clock is " + job.clock + ")");
  }
  // A ROS stack runs in real time inside the board's cgroup: only the emulated clock does that.
  for (const std::string& m : job.methods) {
    if (ctx.IsRosMethod(m) && job.clock != "emulated") {
      ctx.Fail(root["clock"] ? root["clock"] : root["methods"], "clock",
               "method '" + m + "' is a ROS stack: it runs on the emulated clock only (its processes run in real time "
               "inside the board's cgroup); set clock: emulated");
    }
  }
  for (const auto& [name, stack] : job.ros_methods) {
    if (std::find(job.methods.begin(), job.methods.end(), name) == job.methods.end())
      ctx.Fail(root["ros_methods"], "ros_methods." + name, "defined but not listed in methods");
  }
  if (const YAML::Node bag = root["rosbag"]) {
    if (job.ros_methods.empty()) ctx.Fail(bag, "rosbag", "records the topics of ROS methods; this job has none");
    const std::string dir = Scalar(ctx, bag, "rosbag");
    const fs::path given(dir);
    job.rosbag_dir = fs::weakly_canonical(given.is_absolute() ? given : ctx.roots().front() / given).string();
  }
  if (root["timeout_s"]) job.timeout_s = Number(ctx, root["timeout_s"], "timeout_s", 0, kMaxTimeoutS);
  if (root["wind"]) job.wind = Wind(ctx, root["wind"]);
  if (root["odometry_noise"])
    job.odometry_noise =
        Choices(ctx, root["odometry_noise"], "odometry_noise", kOdometryNoisePresets, "odometry noise preset").front();
  if (root["policy"]) {
    job.policy = Policy(ctx, root["policy"], "policy");
  }
  if (root["collect"]) {
    if (Scalar(ctx, root["collect"], "collect") != "rollouts") {
      ctx.Fail(root["collect"], "collect", "the only collection is 'rollouts'");
    }
    job.collect = CollectSpec{};
    if (job.methods != std::vector<std::string>{"enavi"} && job.methods != std::vector<std::string>{"learned"}) {
      ctx.Fail(root["methods"], "methods",
               "a collection job flies one method that records rollouts: [enavi] (its frequency policy) or "
               "[learned] (a nav policy)");
    }
    if (job.clock != "virtual") {
      ctx.Fail(root["clock"], "clock", "rollouts are recorded on the virtual clock only");
    }
    if (job.policy.empty()) ctx.Fail(root, "policy", "a collection job names its policy");
    if (root["sample"]) job.collect->sample = Bool(ctx, root["sample"], "sample");
  } else if (root["sample"]) {
    ctx.Fail(root["sample"], "sample", "only with collect: rollouts");
  }
  if (root["world_params"]) job.world_params = StringMap(ctx, root["world_params"], "world_params");
  if (root["overrides"]) job.overrides = Tunables(ctx, root["overrides"], "overrides", job.methods);
  if (root["labels"]) job.labels = Labels(ctx, root["labels"]);
  if (const YAML::Node list = root["episode_overrides"]) {
    if (!list.IsSequence()) ctx.Fail(list, "episode_overrides", "expected a list");
    for (std::size_t i = 0; i < list.size(); ++i) job.episode_overrides.push_back(Override(ctx, list[i], i, job.methods));
  }
  // A rollout records the policy's own decisions; E-Navi's least-load rule (an ablation) makes
  // none, so every episode of such a job would fail on its worker.
  if (job.collect) {
    const auto rule = [](const std::map<std::string, double>& o) {
      const auto it = o.find("strategy.least_load");
      return it != o.end() && it->second != 0.0;
    };
    const std::string reason = "a collection job records the policy's decisions; the least-load rule takes them instead";
    if (rule(job.overrides)) ctx.Fail(root["overrides"], "overrides.strategy.least_load", reason);
    for (std::size_t i = 0; i < job.episode_overrides.size(); ++i) {
      if (rule(job.episode_overrides[i].overrides)) {
        ctx.Fail(root["episode_overrides"][i], "episode_overrides[" + std::to_string(i) + "].overrides.strategy.least_load",
                 reason);
      }
    }
  }

  // Each factor is bounded above, so the product cannot overflow before this check.
  const std::size_t size = job.MatrixSize();
  if (job.episodes.empty() && size > options.max_episodes) {
    ctx.Fail(root["seeds"], "matrix",
             std::to_string(job.boards.size()) + " boards x " +
                 std::to_string(job.scenarios.size()) + " scenarios x " +
                 std::to_string(job.methods.size()) + " methods x " +
                 std::to_string(job.seeds.size()) + " seeds = " + std::to_string(size) +
                 " episodes, above the limit " + std::to_string(options.max_episodes));
  }
  return job;
}

JobSpec LoadJobSpec(const std::filesystem::path& path, const JobSpecOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw JobSpecError(path.string() + ":1: file: cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseJobSpec(text.str(), path.string(), options);
}

bool IsPolicyHashRef(const std::string& policy) {
  const std::string prefix = kPolicyHashPrefix;
  if (policy.size() != prefix.size() + 64 || policy.rfind(prefix, 0) != 0) return false;
  return std::all_of(policy.begin() + static_cast<std::ptrdiff_t>(prefix.size()), policy.end(),
                     [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::vector<EpisodeSpec> ExpandJob(const JobSpec& job) {
  std::vector<EpisodeSpec> episodes;
  episodes.reserve(job.MatrixSize());
  // The matrix as a list of (board, scenario, seed), or the explicit list.
  std::vector<EpisodePick> picks = job.episodes;
  if (picks.empty()) {
    for (const auto& board : job.boards) {
      for (const auto& scenario : job.scenarios) picks.push_back({board, scenario, 0});
    }
  }
  for (const auto& pick : picks) {
    const std::string& board = pick.board;
    const ScenarioEntry& scenario = pick.scenario;
    {
      for (const auto& method : job.methods) {
        const std::vector<std::uint64_t> seeds =
            job.episodes.empty() ? job.seeds : std::vector<std::uint64_t>{pick.seed};
        for (const std::uint64_t seed : seeds) {
          EpisodeSpec e;
          e.world = scenario.world;
          e.seed = seed;
          e.world_params = job.world_params;
          for (const auto& [k, v] : scenario.params) e.world_params[k] = v;
          e.start = scenario.start;
          e.goal = scenario.goal;
          e.units = scenario.units;
          e.scale = scenario.scale;
          e.up = scenario.up;
          e.recenter = scenario.recenter;
          e.model_path = scenario.model_path;
          e.board = board;
          e.method = method;
          e.clock = job.clock;
          e.cost = job.cost;
          e.dilation = job.dilation;
          e.speed_probe = job.speed_probe;
          e.wind = job.wind;
          e.odometry_noise = job.odometry_noise;
          e.timeout_s = job.timeout_s;
          e.policy = job.policy;
          e.overrides = job.overrides;
          if (const auto ros = job.ros_methods.find(method); ros != job.ros_methods.end()) {
            e.ros = ros->second;
            e.rosbag_dir = job.rosbag_dir;
          }
          for (const auto& o : job.episode_overrides) {
            if (!Matches(o, e)) continue;
            if (o.timeout_s) e.timeout_s = *o.timeout_s;
            if (o.dilation) e.dilation = *o.dilation;
            if (o.policy) e.policy = *o.policy;
            for (const auto& [k, v] : o.overrides) e.overrides[k] = v;
            for (const auto& [k, v] : o.world_params) e.world_params[k] = v;
          }
          // Collection: the policy samples its actions (a named tunable of the method).
          if (job.collect)
            e.overrides[e.method == "learned" ? "learned.explore" : "strategy.explore"] = job.collect->sample ? 1.0 : 0.0;
          episodes.push_back(std::move(e));
        }
      }
    }
  }
  return episodes;
}

std::string LabelError(const std::string& key, const std::string& value) {
  auto in = [](const std::string& text, const char* extra) {
    return std::all_of(text.begin(), text.end(), [extra](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || std::strchr(extra, c) != nullptr;
    });
  };
  if (key.empty() || key.size() > 63) return "label keys have 1..63 characters";
  const bool key_ok = in(key, "_.-") &&
                      std::none_of(key.begin(), key.end(), [](char c) { return std::isupper(static_cast<unsigned char>(c)); }) &&
                      std::isalnum(static_cast<unsigned char>(key.front()));
  if (!key_ok) return "label keys are lower-case letters, digits and _ . - (starting with a letter or digit)";
  if (value.empty() || value.size() > 128) return "label values have 1..128 characters";
  if (!in(value, "_.:/@+-")) return "label values are letters, digits and _ . : / @ + -";
  return "";
}

std::pair<std::string, std::string> ParseLabelFilter(const std::string& text,
                                                     const std::string& field) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) {
    throw std::invalid_argument(field + ": '" + text + "': expected key=value");
  }
  std::string key = text.substr(0, eq), value = text.substr(eq + 1);
  if (const std::string error = LabelError(key, value); !error.empty()) {
    throw std::invalid_argument(field + ": '" + text + "': " + error);
  }
  return {std::move(key), std::move(value)};
}

}  // namespace enavi::api
