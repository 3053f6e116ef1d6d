// The pybind11 module novaphy._novaphy: thin wrappers over the engine; novaphy.Error -> ValueError.
#include "bindings/bindings.h"
#include "engine/model/error.h"

PYBIND11_MODULE(_novaphy, m) {
  namespace py = pybind11;
  m.doc() = "NovaPhy: batched articulated-body physics in reduced coordinates (Featherstone).";
  py::register_exception<novaphy::Error>(m, "Error", PyExc_ValueError);
  novaphy::python::bind_model(m);
  novaphy::python::bind_builder(m);
  novaphy::python::bind_mujoco(m);
  novaphy::python::bind_eval(m);
  novaphy::python::bind_collision(m);
  novaphy::python::bind_solver_featherstone(m);
  novaphy::python::bind_solver_maximal(m);
  novaphy::python::bind_shard(m);
}
