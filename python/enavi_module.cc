// The `enavi` Python module's native part (enavi._enavi): EnvCore and NavEnvCore with numpy
// arrays, the nav policy network (for checking an exported network against PyTorch's), and the
// farm's line charts (learning curves drawn as every other plot of the farm). The
// Gymnasium-style classes are in python/enavi/__init__.py.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "navstack/rl/nav_policy.h"
#include "python/env_core.h"
#include "server/report/chart.h"
#include "python/nav_env_core.h"

namespace py = pybind11;
using enavi::python::EnvConfig;
using enavi::python::EnvCore;
using enavi::python::NavEnvConfig;
using enavi::python::NavEnvCore;
using enavi::python::NavTransition;
using enavi::python::Transition;

namespace {

py::tuple ToPython(const Transition& t) {
  py::array_t<double> obs(t.obs.size());
  std::copy(t.obs.data(), t.obs.data() + t.obs.size(), obs.mutable_data());
  py::array_t<std::uint8_t> mask(static_cast<py::ssize_t>(t.mask.size()));
  std::copy(t.mask.begin(), t.mask.end(), mask.mutable_data());
  py::dict info;
  info["action_mask"] = mask;
  info["decision"] = t.t;
  if (!t.end_reason.empty()) info["end_reason"] = t.end_reason;
  for (const auto& [k, v] : t.metrics) info[k.c_str()] = v;
  return py::make_tuple(obs, t.reward, t.terminated, t.truncated, info);
}

// Runs `fn`, which flies the episode to its next decision, without holding the GIL.
template <typename Fn>
auto Released(Fn&& fn) {
  py::gil_scoped_release release;
  return fn();
}

py::tuple NavToPython(const NavEnvCore& env, const NavTransition& t) {
  py::array_t<float> depth({env.height(), env.width()});
  std::copy(t.depth.begin(), t.depth.end(), depth.mutable_data());
  py::array_t<float> state(static_cast<py::ssize_t>(t.state.size()));
  for (Eigen::Index i = 0; i < t.state.size(); ++i) state.mutable_data()[i] = static_cast<float>(t.state[i]);
  py::dict obs;
  obs["depth"] = depth;
  obs["state"] = state;
  py::dict info;
  info["t"] = t.t;
  if (!t.end_reason.empty()) info["end_reason"] = t.end_reason;
  for (const auto& [k, v] : t.metrics) info[k.c_str()] = v;
  return py::make_tuple(obs, t.reward, t.terminated, t.truncated, info);
}

}  // namespace

PYBIND11_MODULE(_enavi, m) {
  m.doc() = "E-Navi frequency adaptation as a step-by-step environment (native core)";
  py::class_<EnvCore>(m, "EnvCore")
      .def(py::init([](const std::string& world, const std::string& board, const std::string& policy,
                       double timeout_s, std::map<std::string, std::string> world_params,
                       std::map<std::string, double> overrides) {
             EnvConfig c;
             c.world = world;
             c.board = board;
             c.policy = policy;
             c.timeout_s = timeout_s;
             c.world_params = std::move(world_params);
             c.overrides = std::move(overrides);
             return std::make_unique<EnvCore>(std::move(c));
           }),
           py::arg("world"), py::arg("board"), py::arg("policy"), py::arg("timeout_s"),
           py::arg("world_params"), py::arg("overrides"))
      .def("reset", [](EnvCore& e, std::uint64_t seed) { return ToPython(Released([&] { return e.Reset(seed); })); })
      .def("step", [](EnvCore& e, int action) { return ToPython(Released([&] { return e.Step(action); })); })
      .def_property_readonly("obs_size", &EnvCore::obs_size)
      .def_property_readonly("action_size", &EnvCore::action_size);

  py::class_<NavEnvCore>(m, "NavEnvCore")
      .def(py::init([](const std::string& world, const std::string& board, int decimation, bool zero_latency,
                       std::int64_t multiply_adds, double timeout_s, std::map<std::string, std::string> world_params,
                       std::map<std::string, double> overrides) {
             NavEnvConfig c;
             c.world = world;
             c.board = board;
             c.decimation = decimation;
             c.zero_latency = zero_latency;
             c.multiply_adds = multiply_adds;
             c.timeout_s = timeout_s;
             c.world_params = std::move(world_params);
             c.overrides = std::move(overrides);
             return std::make_unique<NavEnvCore>(std::move(c));
           }),
           py::arg("world"), py::arg("board"), py::arg("decimation"), py::arg("zero_latency"),
           py::arg("multiply_adds"), py::arg("timeout_s"), py::arg("world_params"), py::arg("overrides"))
      .def("reset",
           [](NavEnvCore& e, std::uint64_t seed) { return NavToPython(e, Released([&] { return e.Reset(seed); })); })
      .def("step", [](NavEnvCore& e, const Eigen::VectorXd& action) {
        return NavToPython(e, Released([&] { return e.Step(action); }));
      })
      .def_property_readonly("width", &NavEnvCore::width)
      .def_property_readonly("height", &NavEnvCore::height)
      .def_property_readonly("multiply_adds", &NavEnvCore::multiply_adds);

  // The network of a nav policy file on one observation: the action in [-1, 1].
  m.def("nav_policy_forward", [](const std::string& path, py::array_t<float, py::array::c_style | py::array::forcecast> depth,
                                 const Eigen::VectorXd& state) {
    const enavi::navstack::rl::NavPolicyNet net = enavi::navstack::rl::LoadNavPolicy(path);
    enavi::navstack::rl::NavObservation obs;
    obs.depth.assign(depth.data(), depth.data() + depth.size());
    if (state.size() != enavi::navstack::rl::kNavStateSize)
      throw std::invalid_argument("state: expected " + std::to_string(enavi::navstack::rl::kNavStateSize) + " values");
    obs.state = state;
    return Eigen::VectorXd(net.Forward(obs));
  });
  // panels: [(title, y_label, [(name, xs, ys), ...]), ...] stacked over one x axis.
  m.def("save_chart_png", [](const std::string& path, const std::string& title, const std::string& x_label,
                             const std::vector<std::tuple<std::string, std::string,
                                                          std::vector<std::tuple<std::string, std::vector<double>, std::vector<double>>>>>& panels) {
    enavi::report::ChartStack stack(title, x_label);
    for (const auto& [panel_title, y_label, series] : panels) {
      enavi::report::Chart& chart = stack.AddPanel(panel_title, y_label);
      for (const auto& [name, xs, ys] : series) {
        if (xs.size() != ys.size()) throw std::invalid_argument("series " + name + ": x and y differ in length");
        chart.AddSeries(name, xs, ys);
      }
    }
    stack.SavePng(path);
  }, py::arg("path"), py::arg("title"), py::arg("x_label"), py::arg("panels"));
  m.def("nav_policy_multiply_adds", [](const std::string& path) {
    return enavi::navstack::rl::LoadNavPolicy(path).multiply_adds();
  });
}
