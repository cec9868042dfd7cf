#include <algorithm>
#include <deque>
#include <mutex>
#include <stdexcept>

#include "navstack/methods/registry.h"

namespace enavi::navstack {
namespace {

void Check(const MethodInfo& m, const std::deque<MethodInfo>& existing) {
  if (m.name.empty()) throw std::invalid_argument("method: empty name");
  for (const MethodInfo& e : existing)
    if (e.name == m.name) throw std::invalid_argument("method '" + m.name + "': registered twice");
  if (!m.make) throw std::invalid_argument("method '" + m.name + "': no factory");
  if (m.cost_family.empty())
    throw std::invalid_argument("method '" + m.name +
                                "': no cost_family (\"navstack\" if its jobs run our stack's code, else a family of "
                                "its own, priced by `enavi calibrate --write-reference`)");
  // Task keys name result fields (task_cpu_util_pct.<key>): a metric name's part, one per task.
  for (int i = 0; i < kTaskCount; ++i) {
    if (!IsNavigationTask(static_cast<TaskId>(i))) continue;
    const std::string& key = m.task_keys[i];
    const bool word = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    });
    if (!word)
      throw std::invalid_argument("method '" + m.name + "': task key '" + key + "' of task " +
                                  std::string(TaskName(static_cast<TaskId>(i))) +
                                  " is not a name of lower-case letters, digits and '_'");
    for (int j = 0; j < i; ++j)
      if (IsNavigationTask(static_cast<TaskId>(j)) && m.task_keys[j] == key)
        throw std::invalid_argument("method '" + m.name + "': task key '" + key + "' names two tasks");
  }
  for (const MethodTunable& t : m.tunables)
    if (!(t.min <= t.default_value && t.default_value <= t.max))
      throw std::invalid_argument("method '" + m.name + "': tunable " + t.name + " default " +
                                  std::to_string(t.default_value) + " is outside [" + std::to_string(t.min) + ", " +
                                  std::to_string(t.max) + "]");
}

// The built-in methods: the folders navstack/methods/CMakeLists.txt adds.
std::deque<MethodInfo> BuiltinMethods() {
  std::deque<MethodInfo> out;
  for (MethodInfo m : BuiltinMethodList()) {
    Check(m, out);
    out.push_back(std::move(m));
  }
  return out;
}

// A deque: registering a method never moves the ones already handed out.
std::deque<MethodInfo>& Registry() {
  static std::deque<MethodInfo> methods = BuiltinMethods();
  return methods;
}

std::mutex& RegistryMutex() {
  static std::mutex m;
  return m;
}

}  // namespace

const std::deque<MethodInfo>& Methods() {
  std::lock_guard<std::mutex> lock(RegistryMutex());
  return Registry();
}

std::vector<std::string> MethodNames() {
  std::vector<std::string> names;
  for (const MethodInfo& m : Methods()) names.push_back(m.name);
  return names;
}

const MethodInfo* FindMethod(std::string_view name) {
  for (const MethodInfo& m : Methods())
    if (m.name == name) return &m;
  return nullptr;
}

void RegisterMethod(MethodInfo method) {
  std::lock_guard<std::mutex> lock(RegistryMutex());
  std::deque<MethodInfo>& methods = Registry();
  Check(method, methods);
  methods.push_back(std::move(method));
}

void ConfigureMethod(const MethodInfo& info, const MethodSetup& setup, MethodOptions* options) {
  if (info.configure) info.configure(setup, options);
  options->seed = setup.seed;
  options->policy = setup.policy;
  options->record_rollout = setup.record_rollout;
  options->decisions = setup.decisions;
  options->nav_policy = setup.nav_policy;
  for (const MethodTunable& t : info.tunables) options->params[t.name] = t.default_value;
}

}  // namespace enavi::navstack
