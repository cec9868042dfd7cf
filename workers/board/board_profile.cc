#include "workers/board/board_profile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <yaml-cpp/yaml.h>

#include "api/yaml_read.h"

namespace enavi::board {

// Generated from profiles/*.yaml by cmake/EmbedFiles.cmake.
const std::map<std::string, std::string>& EmbeddedBoardFiles();

namespace {

constexpr const char* kReferenceFile = "reference_costs.yaml";

using api::YamlReader;

// A positive number of at most `max`, "must be > 0.0 (got ...)" otherwise.
double Positive(const YamlReader& r, const YamlReader::Map& m, const std::string& key, double max) {
  return r.Range(m.Get(key), m.Field(key), 0.0, max, true);
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
  const YamlReader r(source);
  const YamlReader::Map top(r, r.Load(yaml_text), "",
                            {"id", "name", "cpu", "cores", "clock_ghz", "memory_gb", "paper_gflops", "per_core_speed", "notes"});
  BoardProfile b;
  b.id = r.String(top.Get("id"), "id");
  b.name = r.String(top.Get("name"), "name");
  b.cpu = r.String(top.Get("cpu"), "cpu");
  if (r.Scalar(top.Get("cores"), "cores") == "auto") {
    b.is_host = true;
    b.cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  } else {
    b.cores = static_cast<int>(r.Integer(top.Get("cores"), "cores"));
    if (b.cores < 1 || b.cores > 256) r.Fail(top.Get("cores"), "cores", "must be in [1, 256] (got " + std::to_string(b.cores) + ")");
  }
  if (top.Has("clock_ghz") && r.Scalar(top.Get("clock_ghz"), "clock_ghz") != "auto") b.clock_ghz = Positive(r, top, "clock_ghz", 10);
  if (top.Has("memory_gb") && r.Scalar(top.Get("memory_gb"), "memory_gb") != "auto") Positive(r, top, "memory_gb", 1e6);
  if (top.Has("paper_gflops") && !top.Get("paper_gflops").IsNull()) b.paper_gflops = Positive(r, top, "paper_gflops", 1e6);
  const YamlReader::Map speed(r, top.Get("per_core_speed"), "per_core_speed",
                              {"value", "benchmark", "board_score", "reference_score", "sources"});
  b.per_core_speed = Positive(r, speed, "value", 100);
  if (speed.Has("benchmark")) b.speed_benchmark = r.String(speed.Get("benchmark"), speed.Field("benchmark"), 4096);
  if (top.Has("notes")) b.notes = r.String(top.Get("notes"), "notes", 65536);
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

const ReferenceCosts::Coefficients& ReferenceCosts::For(const std::string& family) const {
  const auto it = families.find(family);
  if (it != families.end()) return it->second;
  std::string known;
  for (const auto& [name, c] : families) known += (known.empty() ? "" : ", ") + name;
  throw std::invalid_argument("reference costs " + calibration_id + ": no prices for cost family '" + family +
                              "' (known: " + known + "): refit with `enavi calibrate --write-reference`");
}

namespace {

// One family's ns_per_job (every task) and ns_per_unit (known units; absent ones cost 0).
ReferenceCosts::Coefficients ParseFamily(const YamlReader& r, const YAML::Node& node, const std::string& field) {
  constexpr double kMaxNs = 1e12;
  const YamlReader::Map top(r, node, field, {"ns_per_job", "ns_per_unit"});
  ReferenceCosts::Coefficients c;
  const YAML::Node& jobs = top.Get("ns_per_job");
  if (!jobs.IsMap())
    r.Fail(jobs, top.Field("ns_per_job"),
           "must map each task (perception, planning, collision, difference, eci, adapter) to its ns per job; a "
           "single number is the format before per-task overheads: refit with `enavi calibrate --write-reference`");
  const YamlReader::Map per_task(r, jobs, top.Field("ns_per_job"), {});
  for (const auto& kv : jobs) {
    const std::string key = kv.first.Scalar();
    if (std::find(navstack::kTaskNames.begin(), navstack::kTaskNames.end(), key) == navstack::kTaskNames.end())
      r.Fail(kv.first, per_task.Field(YamlReader::Shown(key)), "unknown task");
  }
  for (std::size_t t = 0; t < navstack::kTaskNames.size(); ++t) {
    const std::string key(navstack::kTaskNames[t]);
    c.ns_per_job[t] = r.Range(per_task.Get(key), per_task.Field(key), 0.0, kMaxNs);
  }
  const YamlReader::Map per_unit(r, top.Get("ns_per_unit"), top.Field("ns_per_unit"), {});
  for (const auto& kv : per_unit.node()) {
    const std::string key = kv.first.Scalar();
    const auto name_it = std::find(navstack::kWorkUnitNames.begin(), navstack::kWorkUnitNames.end(), key);
    if (name_it == navstack::kWorkUnitNames.end()) r.Fail(kv.first, per_unit.Field(YamlReader::Shown(key)), "unknown work unit");
    c.ns_per_unit[name_it - navstack::kWorkUnitNames.begin()] = r.Range(kv.second, per_unit.Field(key), 0.0, kMaxNs);
  }
  return c;
}

}  // namespace

ReferenceCosts ParseReferenceCosts(const std::string& yaml_text, const std::string& source) {
  const YamlReader r(source);
  const YAML::Node root = r.Load(yaml_text);
  if (root.IsMap() && root["ns_per_job"])
    r.Fail(root["ns_per_job"], "ns_per_job",
           "one set of prices for every method is the format before cost families: refit with `enavi calibrate "
           "--write-reference`");
  const YamlReader::Map top(r, root, "", {"reference_cpu", "calibration_id", "families"});
  ReferenceCosts costs;
  costs.reference_cpu = r.String(top.Get("reference_cpu"), "reference_cpu");
  costs.calibration_id = r.String(top.Get("calibration_id"), "calibration_id");
  const YamlReader::Map families(r, top.Get("families"), "families", {});
  for (const auto& kv : families.node()) {
    const std::string name = kv.first.Scalar();
    costs.families[name] = ParseFamily(r, kv.second, families.Field(YamlReader::Shown(name)));
  }
  if (costs.families.empty()) r.Fail(top.Get("families"), "families", "must name at least one cost family");
  return costs;
}

ReferenceCosts LoadReferenceCosts() {
  const auto& files = EmbeddedBoardFiles();
  const auto it = files.find(kReferenceFile);
  if (it == files.end()) throw std::logic_error("reference_costs.yaml is not embedded in this binary");
  return ParseReferenceCosts(it->second, std::string("workers/board/profiles/") + kReferenceFile);
}

navstack::WorkCountCostModel::Coefficients Scaled(navstack::WorkCountCostModel::Coefficients c, double factor) {
  for (double& v : c.ns_per_job) v *= factor;
  for (double& v : c.ns_per_unit) v *= factor;
  return c;
}

navstack::WorkCountCostModel::Coefficients BoardCoefficients(const BoardProfile& board, const ReferenceCosts& reference,
                                                             const std::string& family) {
  return Scaled(reference.For(family), 1.0 / board.per_core_speed);
}

}  // namespace enavi::board
