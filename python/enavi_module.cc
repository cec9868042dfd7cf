// The `enavi` Python module's native part (enavi._enavi): EnvCore with numpy arrays. The
// Gymnasium-style classes are in python/enavi/__init__.py.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "python/env_core.h"

namespace py = pybind11;
using enavi::python::EnvConfig;
using enavi::python::EnvCore;
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
      // Both fly the episode to its next decision: the GIL is released meanwhile.
      .def("reset", [](EnvCore& e, std::uint64_t seed) {
             Transition t;
             {
               py::gil_scoped_release release;
               t = e.Reset(seed);
             }
             return ToPython(t);
           })
      .def("step", [](EnvCore& e, int action) {
             Transition t;
             {
               py::gil_scoped_release release;
               t = e.Step(action);
             }
             return ToPython(t);
           })
      .def_property_readonly("obs_size", &EnvCore::obs_size)
      .def_property_readonly("action_size", &EnvCore::action_size);
}
