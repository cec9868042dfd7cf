#include "workers/board/host_calibration.h"

#include <sys/utsname.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "api/atomic_file.h"
#include "api/fixed.h"
#include "api/json_read.h"

namespace enavi::board {
namespace {

constexpr const char* kFormat = "enavi-host-calibration";

std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::string(v) : std::string();
}

// The fit's prices by name (a task's per-job overhead, a unit's price), as written and read.
template <typename Names, typename Values>
nlohmann::json PricesJson(const Names& names, const Values& values) {
  nlohmann::json out = nlohmann::json::object();
  for (std::size_t i = 0; i < names.size(); ++i) out[std::string(names[i])] = values[i];
  return out;
}

template <typename Names, typename Values>
void ReadPrices(const api::JsonReader& r, const nlohmann::json& fitted, const std::string& family, const char* key,
                const Names& names, Values& values) {
  const std::string parent = api::JsonReader::Join("fitted", family);
  const std::string where = api::JsonReader::Join(parent, key);
  const nlohmann::json& prices = r.Object(r.Field(fitted, parent, key), where);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string name(names[i]);
    const std::string field = api::JsonReader::Join(where, name);
    values[i] = r.Number(r.Field(prices, where, name), field);
    if (!(values[i] >= 0)) r.Fail(field, "is negative");
  }
}

}  // namespace

std::string CalibrationPath(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const std::string env = Env("ENAVI_CALIBRATION"); !env.empty()) return env;
  if (const std::string xdg = Env("XDG_STATE_HOME"); !xdg.empty()) return xdg + "/enavi/calibration.json";
  const std::string home = Env("HOME");
  if (home.empty())
    throw std::invalid_argument(
        "host calibration: no file given and neither ENAVI_CALIBRATION, XDG_STATE_HOME nor HOME is set");
  return home + "/.local/state/enavi/calibration.json";
}

void SaveHostCalibration(const HostCalibration& c, const std::string& path) {
  nlohmann::json j;
  j["format"] = kFormat;
  j["version"] = HostCalibration::kFormatVersion;
  j["relative_speed"] = c.relative_speed;
  if (c.probe_speed > 0) j["probe_speed"] = c.probe_speed;
  j["cpu_model"] = c.cpu_model;
  j["kernel"] = c.kernel;
  j["date"] = c.date;
  j["reference_calibration_id"] = c.reference_calibration_id;
  j["samples"] = c.samples;
  j["r2"] = c.r2;
  j["fitted"] = nlohmann::json::object();
  for (const auto& [family, f] : c.fitted) {
    j["fitted"][family]["ns_per_job"] = PricesJson(navstack::kTaskNames, f.ns_per_job);
    j["fitted"][family]["ns_per_unit"] = PricesJson(navstack::kWorkUnitNames, f.ns_per_unit);
  }
  for (const auto& [task, t] : c.tasks)
    j["tasks"][task] = {{"jobs", t.jobs}, {"mean_s", t.mean_s}, {"p99_s", t.p99_s}, {"max_s", t.max_s}};
  const std::filesystem::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  try {
    api::WriteFileAtomic(p, j.dump(2) + "\n");
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("host calibration: ") + e.what());
  }
}

HostCalibration LoadHostCalibration(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot read the host calibration file");
  std::ostringstream text;
  text << in.rdbuf();
  const nlohmann::json j = api::ParseJson(text.str(), path);
  const api::JsonReader r(path);
  r.Object(j, "");
  const nlohmann::json* format = r.Optional(j, "", "format");
  if (format == nullptr || *format != kFormat) r.Fail("format", std::string("is not '") + kFormat + "'");
  const auto version = r.Integer(r.Field(j, "", "version"), "version");
  if (version != HostCalibration::kFormatVersion)
    r.Fail("version", "is " + std::to_string(version) + ", this build reads " +
                          std::to_string(HostCalibration::kFormatVersion) +
                          " (since version 2 the fit has one ns per job for each task, since 3 one fit per cost "
                          "family): run `enavi calibrate` again");
  HostCalibration c;
  c.relative_speed = r.Number(r.Field(j, "", "relative_speed"), "relative_speed");
  if (!(c.relative_speed > 0.01 && c.relative_speed < 100))
    r.Fail("relative_speed", "is " + std::to_string(c.relative_speed) + ", outside (0.01, 100)");
  if (const nlohmann::json* probe = r.Optional(j, "", "probe_speed")) {
    c.probe_speed = r.Number(*probe, "probe_speed");
    if (!(c.probe_speed > 0.01 && c.probe_speed < 100))
      r.Fail("probe_speed", "is " + std::to_string(c.probe_speed) + ", outside (0.01, 100)");
  }
  c.cpu_model = r.String(r.Field(j, "", "cpu_model"), "cpu_model");
  c.kernel = r.String(r.Field(j, "", "kernel"), "kernel");
  c.date = r.String(r.Field(j, "", "date"), "date");
  c.reference_calibration_id = r.String(r.Field(j, "", "reference_calibration_id"), "reference_calibration_id");
  c.samples = static_cast<int>(r.Integer(r.Field(j, "", "samples"), "samples"));
  c.r2 = r.Number(r.Field(j, "", "r2"), "r2");
  const nlohmann::json& fitted = r.Object(r.Field(j, "", "fitted"), "fitted");
  for (const auto& [family, prices] : fitted.items()) {
    r.Object(prices, api::JsonReader::Join("fitted", family));
    auto& f = c.fitted[family];
    ReadPrices(r, prices, family, "ns_per_job", navstack::kTaskNames, f.ns_per_job);
    ReadPrices(r, prices, family, "ns_per_unit", navstack::kWorkUnitNames, f.ns_per_unit);
  }
  if (const nlohmann::json* tasks = r.Optional(j, "", "tasks")) {
    for (const auto& [task, t] : r.Object(*tasks, "tasks").items()) {
      const std::string where = api::JsonReader::Join("tasks", task);
      TaskTiming timing;
      timing.jobs = static_cast<int>(r.Integer(r.Field(t, where, "jobs"), where + ".jobs"));
      timing.mean_s = r.Number(r.Field(t, where, "mean_s"), where + ".mean_s");
      timing.p99_s = r.Number(r.Field(t, where, "p99_s"), where + ".p99_s");
      timing.max_s = r.Number(r.Field(t, where, "max_s"), where + ".max_s");
      c.tasks[task] = timing;
    }
  }
  return c;
}

std::string HostCpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? std::string() : line.substr(std::min(line.size(), colon + 2));
    }
  return "unknown";
}

std::string HostKernel() {
  utsname uts{};
  if (uname(&uts) != 0) return "unknown";
  return uts.release;
}

CalibrationCheck CheckHostCalibration(const std::string& path, const std::string& cpu_model,
                                      const std::string& reference_calibration_id) {
  CalibrationCheck check;
  check.path = path;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    check.status = CalibrationCheck::Status::kMissing;
    check.message = "no host calibration at " + path + "; run `enavi calibrate` on this machine first";
    return check;
  }
  try {
    check.calibration = LoadHostCalibration(path);
  } catch (const std::invalid_argument& e) {
    check.status = CalibrationCheck::Status::kInvalid;
    check.message = std::string("unusable host calibration: ") + e.what() + "; run `enavi calibrate` to rewrite it";
    return check;
  }
  const HostCalibration& c = *check.calibration;
  std::string why;
  if (c.cpu_model != cpu_model) why = "it was measured on '" + c.cpu_model + "', this machine is '" + cpu_model + "'";
  if (c.reference_calibration_id != reference_calibration_id) {
    why += (why.empty() ? "" : ", and ") + std::string("it was measured against reference costs '") +
           c.reference_calibration_id + "', this build embeds '" + reference_calibration_id + "'";
  }
  if (!why.empty()) {
    check.status = CalibrationCheck::Status::kStale;
    check.message = "stale host calibration " + path + " (" + c.date + "): " + why + "; run `enavi calibrate` again";
    return check;
  }
  check.status = CalibrationCheck::Status::kValid;
  return check;
}

CalibrationCheck CheckHostCalibration(const std::string& path) {
  return CheckHostCalibration(path, HostCpuModel(), LoadReferenceCosts().calibration_id);
}

double SpeedVsHost(const BoardProfile& board, double host_speed) {
  if (board.is_host) return 1.0;
  return board.per_core_speed / host_speed;
}

DriftText DescribeDrift(const HostCalibration& host, const SpeedProbe& probe) {
  const SpeedDrift d = DriftSinceCalibration(host, probe.speed);
  DriftText text;
  text.drift = "this host's speed moved " + std::string(d.ratio >= 1 ? "+" : "") + api::Fixed(100 * (d.ratio - 1), 1) +
               " % since its calibration (" + host.date + "; probe " + api::Fixed(d.probed, 3) +
               " x the reference core now, " + api::Fixed(d.at_calibration, 3) + " then)";
  std::string cpus;
  for (const auto& [cpu, s] : probe.per_cpu)
    cpus += (cpus.empty() ? "CPU " : ", CPU ") + std::to_string(cpu) + " " + api::Fixed(s, 3);
  text.spread = "its CPUs differ by " + api::Fixed(100 * probe.Spread(), 1) + " % (" + cpus + ")";
  return text;
}

double SpeedProbe::Spread() const {
  if (per_cpu.size() < 2) return 0;
  const auto [lo, hi] = std::minmax_element(per_cpu.begin(), per_cpu.end(),
                                            [](const auto& a, const auto& b) { return a.second < b.second; });
  return hi->second / lo->second - 1;
}

SpeedDrift DriftSinceCalibration(const HostCalibration& host, double probed) {
  if (!(probed > 0 && std::isfinite(probed)))
    throw std::invalid_argument("host speed probe: speed " + std::to_string(probed) + " is not a positive number");
  SpeedDrift d;
  d.probed = probed;
  d.at_calibration = host.probe_speed > 0 ? host.probe_speed : host.relative_speed;
  d.ratio = probed / d.at_calibration;
  d.host_speed = host.relative_speed * d.ratio;
  return d;
}

TaskTiming SummariseTimes(std::vector<double> seconds) {
  TaskTiming t;
  if (seconds.empty()) return t;
  std::sort(seconds.begin(), seconds.end());
  t.jobs = static_cast<int>(seconds.size());
  double sum = 0;
  for (double s : seconds) sum += s;
  t.mean_s = sum / static_cast<double>(seconds.size());
  const std::size_t i99 = std::min(seconds.size() - 1,
                                   static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(seconds.size()))) - 1);
  t.p99_s = seconds[i99];
  t.max_s = seconds.back();
  return t;
}

}  // namespace enavi::board
