// novaphy.solvers.SolverSemiImplicit and SolverXPBD: the solvers in maximal coordinates, their keyword arguments
// mirrored into solver.settings (names as Newton's where the meaning is the same).
#include <memory>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "engine/solver/semi_implicit/solver_semi_implicit.h"
#include "engine/solver/xpbd/solver_xpbd.h"

namespace novaphy::python {

namespace {

// what both solvers' classes share: step (the GIL released, a float32 state widened and rounded back), settings,
// joint_support, diverged
// a UserWarning naming what of the model the solver does not model
template <typename Solver>
Solver* warned(std::unique_ptr<Solver> solver) {
  const std::vector<std::string>& ignored = solver->ignored();
  if (ignored.empty()) return solver.release();
  std::string text = std::string(ignored.size() == 1 ? "1 thing" : std::to_string(ignored.size()) + " things") +
                     " of the model not modelled by this solver (solver.ignored lists them): " + ignored[0];
  if (ignored.size() > 1) text += ", ...";
  if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 1) != 0) throw py::error_already_set();
  return solver.release();
}

template <typename Solver>
void def_maximal(py::class_<Solver>& c) {
  def_step<Solver>(c,
                   "Advances state_in by dt into state_out (they may be the same State): the bodies' body_q and "
                   "body_qd, and joint_q and joint_qd from them; one step at a time per solver (another thread's "
                   "raises).");
  c.def_readwrite("settings", &Solver::settings)
      .def("joint_support", [](const Solver& self) { return self.joint_support(); })
      .def_property_readonly(
          "ignored", [](const Solver& self) { return self.ignored(); },
          "What of the model the solver does not model, by name (a joint's armature and dry friction).")
      .def_property_readonly(
          "diverged",
          [](py::object self) {
            auto& flags = const_cast<std::vector<std::uint8_t>&>(self.cast<const Solver&>().diverged());
            return view(flags.data(), static_cast<int>(flags.size()), 1, self, false);
          },
          "Per world: 1 where the last step's divergence guard fired (a read-only view).");
}

}  // namespace

void bind_solver_maximal(py::module_& m) {
  NOVAPHY_BIND_SETTINGS_CLASS(m, SolverSemiImplicitSettings, NOVAPHY_SEMI_IMPLICIT_SETTINGS,
                              "Every knob of SolverSemiImplicit (docs/settings.md); checked at each step.");
  NOVAPHY_BIND_SETTINGS_CLASS(m, SolverXPBDSettings, NOVAPHY_XPBD_SETTINGS,
                              "Every knob of SolverXPBD (docs/settings.md); checked at each step.");

  py::class_<SolverSemiImplicit> semi(
      m, "SolverSemiImplicit",
      "Maximal coordinates: every body integrated semi-implicitly, joints, limits and contacts as sequential-impulse "
      "PGS rows. Enforces every joint type.");
  semi.def(py::init([](const Model& model, Scalar angular_damping, Scalar friction_smoothing, int num_iterations) {
             SolverSemiImplicitSettings settings;
             settings.angular_damping = angular_damping;
             settings.friction_smoothing = friction_smoothing;
             settings.num_iterations = num_iterations;
             return warned(std::make_unique<SolverSemiImplicit>(model, settings));
           }),
           py::arg("model"), py::kw_only(), py::arg("angular_damping") = 0.05, py::arg("friction_smoothing") = 1.0,
           py::arg("num_iterations") = 20, py::keep_alive<1, 2>());
  def_maximal(semi);

  py::class_<SolverXPBD> xpbd(
      m, "SolverXPBD",
      "Maximal coordinates: constraints held at the position level with compliance (XPBD), in substeps. Enforces "
      "every joint type.");
  xpbd.def(py::init([](const Model& model, int iterations, int substeps, Scalar joint_linear_relaxation,
                       Scalar joint_angular_relaxation, Scalar joint_linear_compliance, Scalar joint_angular_compliance,
                       Scalar rigid_contact_relaxation, Scalar angular_damping, bool enable_restitution) {
             SolverXPBDSettings settings;
             settings.iterations = iterations;
             settings.substeps = substeps;
             settings.joint_linear_relaxation = joint_linear_relaxation;
             settings.joint_angular_relaxation = joint_angular_relaxation;
             settings.joint_linear_compliance = joint_linear_compliance;
             settings.joint_angular_compliance = joint_angular_compliance;
             settings.rigid_contact_relaxation = rigid_contact_relaxation;
             settings.angular_damping = angular_damping;
             settings.enable_restitution = enable_restitution;
             return warned(std::make_unique<SolverXPBD>(model, settings));
           }),
           py::arg("model"), py::kw_only(), py::arg("iterations") = SolverXPBDSettings{}.iterations,
           py::arg("substeps") = SolverXPBDSettings{}.substeps,
           py::arg("joint_linear_relaxation") = SolverXPBDSettings{}.joint_linear_relaxation,
           py::arg("joint_angular_relaxation") = SolverXPBDSettings{}.joint_angular_relaxation,
           py::arg("joint_linear_compliance") = 0.0, py::arg("joint_angular_compliance") = 0.0,
           py::arg("rigid_contact_relaxation") = SolverXPBDSettings{}.rigid_contact_relaxation,
           py::arg("angular_damping") = 0.0, py::arg("enable_restitution") = false, py::keep_alive<1, 2>());
  def_maximal(xpbd);
}

}  // namespace novaphy::python
