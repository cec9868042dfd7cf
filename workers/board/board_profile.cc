#include "workers/board/board_profile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <yaml-cpp/yaml.h>

namespace enavi::board {

// Generated from profiles/*.yaml by cmake/EmbedFiles.cmake.
const std::map<std::string, std::string>& EmbeddedBoardFiles();

namespace {

constexpr const char* kReferenceFile = "reference_costs.yaml";

[[noreturn]] void Fail(const std::string& source, const YAML::Node& node, const std::string& field,
                       const std::string& reason) {
  const int line = node.IsDefined() ? node.Mark().line + 1 : 0;
  throw std::invalid_argument(source + ":" + std::to_string(line) + ": " + field + ": " + reason);
}

template <typename T>
T Get(const YAML::Node& parent, const char* key, const std::string& source) {
  const YAML::Node n = parent[key];
  if (!n) Fail(source, parent, key, "missing");
  try {
    return n.as<T>();
  } catch (const YAML::Exception&) {
    Fail(source, n, key, "wrong type");
  }
}

double GetPositive(const YAML::Node& parent, const char* key, const std::string& source, double max) {
  const double v = Get<double>(parent, key, source);
  if (!std::isfinite(v) || v <= 0 || v > max)
    Fail(source, parent[key], key, "must be in (0, " + std::to_string(max) + "], got " + std::to_string(v));
  return v;
}

}  // namespace

std::vector<std::string> KnownBoards() {
  std::vector<std::string> ids;
  for (const auto& [name, text] : EmbeddedBoardFiles()) {
    if (name == kReferenceFile || name.size() < 6 || name.substr(name.size() - 5) != ".yaml") continue;
    ids.push_back(name.substr(0, name.size() - 5));
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

BoardProfile ParseBoardProfile(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  BoardProfile b;
  b.id = Get<std::string>(root, "id", source);
  b.name = Get<std::string>(root, "name", source);
  b.cpu = Get<std::string>(root, "cpu", source);
  const YAML::Node cores = root["cores"];
  if (cores && cores.IsScalar() && cores.Scalar() == "auto") {
    b.is_host = true;
    b.cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  } else {
    b.cores = static_cast<int>(GetPositive(root, "cores", source, 256));
  }
  if (root["clock_ghz"] && root["clock_ghz"].Scalar() != "auto")
    b.clock_ghz = GetPositive(root, "clock_ghz", source, 10);
  if (root["paper_gflops"] && !root["paper_gflops"].IsNull())
    b.paper_gflops = GetPositive(root, "paper_gflops", source, 1e6);
  const YAML::Node speed = root["per_core_speed"];
  if (!speed) Fail(source, root, "per_core_speed", "missing");
  b.per_core_speed = GetPositive(speed, "value", source, 100);
  if (speed["benchmark"]) b.speed_benchmark = speed["benchmark"].as<std::string>();
  if (root["notes"]) b.notes = root["notes"].as<std::string>();
  return b;
}

BoardProfile LoadBoard(const std::string& id) {
  const auto& files = EmbeddedBoardFiles();
  const auto it = files.find(id + ".yaml");
  if (id.empty() || id == "reference_costs" || it == files.end()) {
    std::string known;
    for (const auto& k : KnownBoards()) known += (known.empty() ? "" : ", ") + k;
    throw std::invalid_argument("board: unknown board '" + id + "' (known: " + known + ")");
  }
  BoardProfile b = ParseBoardProfile(it->second, "workers/board/profiles/" + it->first);
  if (b.id != id) throw std::logic_error("board profile " + it->first + " has id " + b.id);
  return b;
}

ReferenceCosts ParseReferenceCosts(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  ReferenceCosts r;
  r.reference_cpu = Get<std::string>(root, "reference_cpu", source);
  r.calibration_id = Get<std::string>(root, "calibration_id", source);
  // One overhead per task; the format before them had one number for all.
  const YAML::Node jobs = root["ns_per_job"];
  if (!jobs) Fail(source, root, "ns_per_job", "missing");
  if (!jobs.IsMap())
    Fail(source, jobs, "ns_per_job",
         "must map each task (perception, planning, collision, difference, eci, adapter) to its ns per job; a "
         "single number is the format before per-task overheads: refit with `enavi calibrate --write-reference`");
  for (std::size_t t = 0; t < navstack::kTaskNames.size(); ++t) {
    const std::string key(navstack::kTaskNames[t]);
    const std::string field = "ns_per_job." + key;
    const YAML::Node v = jobs[key];
    if (!v) Fail(source, jobs, field, "missing");
    double ns = 0;
    try {
      ns = v.as<double>();
    } catch (const YAML::Exception&) {
      Fail(source, v, field, "wrong type");
    }
    if (!std::isfinite(ns) || ns < 0) Fail(source, v, field, "must be finite and >= 0");
    r.ns.ns_per_job[t] = ns;
  }
  for (const auto& kv : jobs) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(navstack::kTaskNames.begin(), navstack::kTaskNames.end(), key) == navstack::kTaskNames.end())
      Fail(source, kv.first, "ns_per_job." + key, "unknown task");
  }
  const YAML::Node units = root["ns_per_unit"];
  if (!units || !units.IsMap()) Fail(source, root, "ns_per_unit", "missing or not a map");
  for (const auto& kv : units) {
    const std::string key = kv.first.as<std::string>();
    const auto name_it = std::find(navstack::kWorkUnitNames.begin(), navstack::kWorkUnitNames.end(), key);
    if (name_it == navstack::kWorkUnitNames.end()) Fail(source, kv.first, "ns_per_unit." + key, "unknown work unit");
    const double v = kv.second.as<double>();
    if (!std::isfinite(v) || v < 0) Fail(source, kv.second, "ns_per_unit." + key, "must be finite and >= 0");
    r.ns.ns_per_unit[name_it - navstack::kWorkUnitNames.begin()] = v;
  }
  return r;
}

ReferenceCosts LoadReferenceCosts() {
  const auto& files = EmbeddedBoardFiles();
  const auto it = files.find(kReferenceFile);
  if (it == files.end()) throw std::logic_error("reference_costs.yaml is not embedded in this binary");
  return ParseReferenceCosts(it->second, std::string("workers/board/profiles/") + kReferenceFile);
}

navstack::WorkCountCostModel::Coefficients BoardCoefficients(const BoardProfile& board,
                                                             const ReferenceCosts& reference) {
  navstack::WorkCountCostModel::Coefficients c = reference.ns;
  const double slowdown = 1.0 / board.per_core_speed;
  for (double& v : c.ns_per_job) v *= slowdown;
  for (double& v : c.ns_per_unit) v *= slowdown;
  return c;
}

}  // namespace enavi::board
