// novaphy.solvers.SolverFeatherstone with the seed's keyword arguments mirrored into solver.settings.
#include "engine/solver/solver_featherstone.h"

#include <limits>
#include <sstream>
#include <string>
#include <type_traits>

#include "bindings/bindings.h"
#include "engine/solver/simulate.h"

namespace novaphy::python {

void bind_solver_featherstone(py::module_& m) {
  using Settings = SolverFeatherstoneSettings;
  py::enum_<DivergencePolicy>(m, "DivergencePolicy", "What step does with an articulation that diverged.")
      .value("Raise", DivergencePolicy::Raise, "step raises and writes nothing")
      .value("Flag", DivergencePolicy::Flag, "the articulation keeps its previous state; solver.diverged marks it")
      .value("Reset", DivergencePolicy::Reset,
             "the articulation restarts from the reset state (set_reset_state, set_reset_keyframe; else joint_q0 at "
             "rest)");
  NOVAPHY_BIND_SETTINGS_CLASS(m, SolverFeatherstoneSettings, NOVAPHY_SOLVER_SETTINGS,
                              "Every knob of SolverFeatherstone (docs/settings.md); checked at each step.");

  py::class_<JointSupportMatrix>(m, "JointSupportMatrix", "Which joint types a solver enforces.")
      .def("supports", &JointSupportMatrix::supports, py::arg("joint"))
      .def("__getitem__", &JointSupportMatrix::supports)
      .def_property_readonly("joints",
                             [](const JointSupportMatrix& self) {
                               py::dict d;
                               for (const auto& e : self.entries) d[py::str(e.joint)] = e.supported;
                               return d;
                             })
      .def("__str__", &JointSupportMatrix::to_string)
      .def("__repr__", &JointSupportMatrix::to_string);

  py::class_<SolverFeatherstone> featherstone(
      m, "SolverFeatherstone", "Featherstone articulated-body solver: CRBA + Cholesky, sequential-impulse PGS.");
  featherstone
      .def(py::init([](const Model& model, Scalar angular_damping, int update_mass_matrix_interval,
                       Scalar friction_smoothing, bool use_tile_gemm, bool fuse_cholesky) {
             Settings settings;
             settings.angular_damping = angular_damping;
             settings.update_mass_matrix_interval = update_mass_matrix_interval;
             settings.friction_smoothing = friction_smoothing;
             settings.use_tile_gemm = use_tile_gemm;
             settings.fuse_cholesky = fuse_cholesky;
             return new SolverFeatherstone(model, settings);
           }),
           py::arg("model"), py::kw_only(), py::arg("angular_damping") = 0.05,
           py::arg("update_mass_matrix_interval") = 1, py::arg("friction_smoothing") = 1.0,
           py::arg("use_tile_gemm") = false, py::arg("fuse_cholesky") = true, py::keep_alive<1, 2>())
      .def_readwrite("settings", &SolverFeatherstone::settings)
      .def(
          "set_reset_state",
          [](SolverFeatherstone& self, State& state) {
            const Widened<State> read(state, false);
            self.set_reset_state(state);
          },
          py::arg("state"),
          "The state (its joint_q and joint_qd, copied) an articulation restarts from under on_divergence Reset.")
      .def("set_reset_keyframe", &SolverFeatherstone::set_reset_keyframe, py::arg("keyframe"),
           "The reset state at the model's keyframe of that name: its coordinates and velocities.")
      .def("joint_support", &SolverFeatherstone::joint_support)
      .def_property_readonly(
          "stage_seconds",
          [](const SolverFeatherstone& self) {
            const SolverStageSeconds& t = self.stage_seconds();
            py::dict d;
            d["dynamics"] = t.dynamics;
            d["limit_rows"] = t.limit_rows;
            d["contact_rows"] = t.contact_rows;
            d["solve"] = t.solve;
            d["integrate"] = t.integrate;
            d["steps"] = t.steps;
            return d;
          },
          "Seconds spent in each stage of step while settings.profile_stages is on, and the steps timed.")
      .def("reset_stage_seconds", &SolverFeatherstone::reset_stage_seconds, "Zeroes stage_seconds.")
      .def_property_readonly(
          "serial_seconds", [](const SolverFeatherstone& self) { return serial_seconds_dict(self.serial_seconds()); },
          "Seconds of whole steps and of their parallel work while settings.count_serial_time is on, the steps "
          "timed, and the serial share (the rest over the whole).")
      .def("reset_serial_seconds", &SolverFeatherstone::reset_serial_seconds, "Zeroes serial_seconds.")
      .def_property_readonly("memory_bytes", &SolverFeatherstone::memory_bytes,
                             "Bytes the solver holds: batched blocks, scalar scratch, step vectors.")
      .def_property_readonly(
          "diverged",
          [](py::object self) {
            auto& flags = const_cast<std::vector<std::uint8_t>&>(self.cast<const SolverFeatherstone&>().diverged());
            return view(flags.data(), static_cast<int>(flags.size()), 1, self, false);
          },
          "Per articulation: 1 where the last step's divergence guard fired (a read-only view).");
  def_step<SolverFeatherstone>(featherstone,
                               "Advances state_in by dt into state_out (they may be the same State); one step at a "
                               "time per solver (another thread's raises).");
  m.def(
      "simulate",
      [](CollisionPipeline& pipeline, SolverFeatherstone& solver, State& state, Control& control, Contacts& contacts,
         int substeps, Scalar dt) {
        const int threads = solver.settings.num_threads;
        const ExclusiveCall held_pipeline = pipeline.hold(), held_solver = solver.hold();
        const Widened<State> written(state, true, threads);
        const Widened<Control> read(control, false, threads);
        simulate(pipeline, solver, state, control, contacts, substeps, dt);
      },
      py::arg("pipeline"), py::arg("solver"), py::arg("state"), py::arg("control"), py::arg("contacts"),
      py::arg("substeps") = 1, py::arg("dt") = 0.0, py::call_guard<py::gil_scoped_release>(),
      "substeps steps of dt (0: the model's timestep) of state, in place: each pipeline.collide(state, contacts), "
      "then solver.step(state, state, control, contacts, dt), the same bits as that loop; without the GIL.");
}

}  // namespace novaphy::python
