#include "api/job_spec.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace enavi::api {
namespace {

namespace fs = std::filesystem;

// Error reporting: every message reads FILE:LINE: field: reason.
class Context {
 public:
  Context(std::string file, const JobSpecOptions& options) : file_(std::move(file)), catalog_(options.catalog) {
    std::vector<fs::path> roots = options.allowed_roots;
    if (roots.empty()) roots.push_back(fs::current_path());
    for (const auto& r : roots) roots_.push_back(fs::weakly_canonical(fs::absolute(r)));
  }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& field,
                         const std::string& reason) const {
    const YAML::Mark mark = at.Mark();
    const int line = mark.is_null() ? 1 : mark.line + 1;
    throw JobSpecError(file_ + ":" + std::to_string(line) + ": " + field + ": " + reason);
  }

  const std::vector<fs::path>& roots() const { return roots_; }
  const MethodCatalog& catalog() const { return catalog_; }

 private:
  std::string file_;
  const MethodCatalog& catalog_;
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
  if (!n.IsScalar()) ctx.Fail(n, field, "expected a single value");
  return n.Scalar();
}

std::int64_t Integer(const Context& ctx, const YAML::Node& n, const std::string& field) {
  const std::string text = Scalar(ctx, n, field);
  try {
    std::size_t used = 0;
    const long long v = std::stoll(text, &used, 10);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  ctx.Fail(n, field, "expected an integer, got '" + text + "'");
}

double Number(const Context& ctx, const YAML::Node& n, const std::string& field, double lo,
              double hi) {
  const std::string text = Scalar(ctx, n, field);
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    ctx.Fail(n, field, "expected a number, got '" + text + "'");
  }
  if (!std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream os;
    os << text << " outside [" << lo << ", " << hi << "]";
    ctx.Fail(n, field, os.str());
  }
  return v;
}

// A scalar or a list of scalars, as strings.
std::vector<YAML::Node> Items(const Context& ctx, const YAML::Node& n, const std::string& field) {
  std::vector<YAML::Node> out;
  if (n.IsScalar()) {
    out.push_back(n);
  } else if (n.IsSequence()) {
    for (const auto& item : n) out.push_back(item);
  } else {
    ctx.Fail(n, field, "expected a value or a list");
  }
  return out;
}

// Rejects keys that are not in `allowed` and duplicated keys.
void CheckKeys(const Context& ctx, const YAML::Node& map, const std::string& where,
               std::initializer_list<const char*> allowed) {
  std::set<std::string> seen;
  for (const auto& kv : map) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
    const std::string field = where.empty() ? key : where + "." + key;
    if (!Contains(allowed, key)) {
      ctx.Fail(kv.first, field,
               "unknown key (allowed: " + Join(allowed) + ")");
    }
    if (!seen.insert(key).second) ctx.Fail(kv.first, field, "duplicate key");
  }
}

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
std::string ResolveFile(const Context& ctx, const YAML::Node& n, const std::string& field,
                        const std::string& value, std::initializer_list<const char*> extensions) {
  const fs::path given(value);
  const std::string ext = given.extension().string();
  if (!Contains(extensions, ext)) {
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
  if (!fs::is_regular_file(resolved)) ctx.Fail(n, field, "'" + value + "': no such file");
  return resolved.string();
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

ScenarioEntry Scenario(const Context& ctx, const YAML::Node& n) {
  ScenarioEntry entry;
  if (n.IsMap()) {
    CheckKeys(ctx, n, "scenarios", {"world", "start", "goal", "params"});
    if (!n["world"]) ctx.Fail(n, "scenarios.world", "missing");
    if (n["start"]) entry.start = Point(ctx, n["start"], "scenarios.start");
    if (n["goal"]) entry.goal = Point(ctx, n["goal"], "scenarios.goal");
    if (n["params"]) entry.params = StringMap(ctx, n["params"], "scenarios.params");
  } else if (!n.IsScalar()) {
    ctx.Fail(n, "scenarios", "expected a scenario id, a world file or {world: ...}");
  }
  // Never assign YAML::Node to an existing node: yaml-cpp would overwrite the node it refers to.
  const YAML::Node world_node = n.IsMap() ? n["world"] : n;
  const std::string world = Scalar(ctx, world_node, "scenarios");
  if (Contains(kScenarios, world)) {
    entry.world = world;
  } else if (world.find('/') != std::string::npos || world.find('.') != std::string::npos) {
    entry.world = ResolveFile(ctx, world_node, "scenarios", world, {".yaml", ".yml", ".obj"});
    if (fs::path(world).extension() == ".obj" && (!entry.start || !entry.goal)) {
      ctx.Fail(world_node, "scenarios", "'" + world + "' is an OBJ mesh: give start and goal");
    }
  } else {
    ctx.Fail(world_node, "scenarios",
             "unknown scenario '" + world + "' (known: " + Join(kScenarios) +
                 ", or a .yaml/.obj world file)");
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

EpisodeOverride Override(const Context& ctx, const YAML::Node& n, const std::vector<std::string>& job_methods) {
  const std::string f = "episode_overrides";
  if (!n.IsMap()) ctx.Fail(n, f, "expected a map with match: and settings");
  CheckKeys(ctx, n, f, {"match", "timeout_s", "dilation", "policy", "overrides", "world_params"});
  EpisodeOverride o;
  if (const YAML::Node m = n["match"]) {
    if (!m.IsMap()) ctx.Fail(m, f + ".match", "expected a map of board/scenario/method/seed");
    CheckKeys(ctx, m, f + ".match", {"board", "scenario", "method", "seed"});
    if (m["board"]) o.boards = Choices(ctx, m["board"], f + ".match.board", kBoards, "board");
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
  if (n["dilation"]) o.dilation = Number(ctx, n["dilation"], f + ".dilation", 0.01, kMaxDilation);
  if (n["policy"]) {
    o.policy = ResolveFile(ctx, n["policy"], f + ".policy",
                           Scalar(ctx, n["policy"], f + ".policy"), {".json", ".bin", ".pt"});
  }
  if (n["overrides"]) o.overrides = Tunables(ctx, n["overrides"], f + ".overrides", o.methods.empty() ? job_methods : o.methods);
  if (n["world_params"]) o.world_params = StringMap(ctx, n["world_params"], f + ".world_params");
  return o;
}

bool Matches(const EpisodeOverride& o, const EpisodeSpec& e) {
  auto in = [](const auto& list, const auto& v) {
    return list.empty() || std::find(list.begin(), list.end(), v) != list.end();
  };
  return in(o.boards, e.board) && in(o.scenarios, e.world) && in(o.methods, e.method) &&
         in(o.seeds, e.seed);
}

}  // namespace

JobSpec ParseJobSpec(const std::string& yaml_text, const std::string& file_name,
                     const JobSpecOptions& options) {
  if (options.catalog.methods.empty())
    throw std::logic_error("ParseJobSpec: no method catalog (the composition root passes the registry's)");
  const Context ctx(file_name, options);
  YAML::Node loaded;
  try {
    loaded = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw JobSpecError(file_name + ":" + std::to_string(e.mark.line + 1) + ": yaml: " + e.msg);
  }
  // const: operator[] on a mutable node would insert the keys it looks up.
  const YAML::Node root = loaded;
  if (!root.IsMap()) ctx.Fail(root, "job", "expected a YAML map of name, boards, scenarios, ...");
  CheckKeys(ctx, root, "",
            {"name", "boards", "scenarios", "methods", "seeds", "clock", "cost", "dilation",
             "timeout_s", "policy", "world_params", "overrides", "episode_overrides"});
  for (const char* required : {"boards", "scenarios", "methods", "seeds"}) {
    if (!root[required]) ctx.Fail(root, required, "missing (required)");
  }

  JobSpec job;
  if (root["name"]) {
    job.name = Scalar(ctx, root["name"], "name");
    if (job.name.empty() || job.name.size() > 128) ctx.Fail(root["name"], "name", "1..128 characters");
  } else {
    job.name = fs::path(file_name).stem().string();
  }
  job.boards = Choices(ctx, root["boards"], "boards", kBoards, "board");
  job.methods = Choices(ctx, root["methods"], "methods", MethodNames(ctx), "method");
  for (const auto& item : Items(ctx, root["scenarios"], "scenarios")) {
    ScenarioEntry entry = Scenario(ctx, item);
    for (const auto& other : job.scenarios) {
      if (other.world == entry.world) ctx.Fail(item, "scenarios", "'" + entry.world + "' listed twice");
    }
    job.scenarios.push_back(std::move(entry));
  }
  if (job.scenarios.empty()) ctx.Fail(root["scenarios"], "scenarios", "empty list");
  job.seeds = Seeds(ctx, root["seeds"]);
  if (root["clock"]) job.clock = Choices(ctx, root["clock"], "clock", kClocks, "clock").front();
  if (root["cost"]) job.cost = Choices(ctx, root["cost"], "cost", kCostModes, "cost mode").front();
  if (root["dilation"]) job.dilation = Number(ctx, root["dilation"], "dilation", 0.01, kMaxDilation);
  if (root["timeout_s"]) job.timeout_s = Number(ctx, root["timeout_s"], "timeout_s", 0, kMaxTimeoutS);
  if (root["policy"]) {
    job.policy = ResolveFile(ctx, root["policy"], "policy", Scalar(ctx, root["policy"], "policy"),
                             {".json", ".bin", ".pt"});
  }
  if (root["world_params"]) job.world_params = StringMap(ctx, root["world_params"], "world_params");
  if (root["overrides"]) job.overrides = Tunables(ctx, root["overrides"], "overrides", job.methods);
  if (const YAML::Node list = root["episode_overrides"]) {
    if (!list.IsSequence()) ctx.Fail(list, "episode_overrides", "expected a list");
    for (const auto& item : list) job.episode_overrides.push_back(Override(ctx, item, job.methods));
  }

  // Each factor is bounded above, so the product cannot overflow before this check.
  const std::size_t size = job.MatrixSize();
  if (size > options.max_episodes) {
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

std::vector<EpisodeSpec> ExpandJob(const JobSpec& job) {
  std::vector<EpisodeSpec> episodes;
  episodes.reserve(job.MatrixSize());
  for (const auto& board : job.boards) {
    for (const auto& scenario : job.scenarios) {
      for (const auto& method : job.methods) {
        for (const std::uint64_t seed : job.seeds) {
          EpisodeSpec e;
          e.world = scenario.world;
          e.seed = seed;
          e.world_params = job.world_params;
          for (const auto& [k, v] : scenario.params) e.world_params[k] = v;
          e.start = scenario.start;
          e.goal = scenario.goal;
          e.board = board;
          e.method = method;
          e.clock = job.clock;
          e.cost = job.cost;
          e.dilation = job.dilation;
          e.timeout_s = job.timeout_s;
          e.policy = job.policy;
          e.overrides = job.overrides;
          for (const auto& o : job.episode_overrides) {
            if (!Matches(o, e)) continue;
            if (o.timeout_s) e.timeout_s = *o.timeout_s;
            if (o.dilation) e.dilation = *o.dilation;
            if (o.policy) e.policy = *o.policy;
            for (const auto& [k, v] : o.overrides) e.overrides[k] = v;
            for (const auto& [k, v] : o.world_params) e.world_params[k] = v;
          }
          episodes.push_back(std::move(e));
        }
      }
    }
  }
  return episodes;
}

std::string ScenarioOf(const std::string& world) {
  return Contains(kScenarios, world) ? world : std::string("custom");
}

}  // namespace enavi::api
