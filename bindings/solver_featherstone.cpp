// novaphy.solvers.SolverFeatherstone with the seed's keyword arguments mirrored into solver.settings.
#include "engine/solver_featherstone.h"

#include "bindings/bindings.h"

namespace novaphy::python {

void bind_solver_featherstone(py::module_& m) {
  using Settings = SolverFeatherstoneSettings;
  py::enum_<DivergencePolicy>(m, "DivergencePolicy", "What step does with an articulation that diverged.")
      .value("Raise", DivergencePolicy::Raise, "step raises and writes nothing")
      .value("Flag", DivergencePolicy::Flag, "the articulation keeps its previous state; solver.diverged marks it")
      .value("Reset", DivergencePolicy::Reset, "the articulation restarts from the model's joint_q0 at rest");
  py::class_<Settings>(m, "SolverFeatherstoneSettings", "Every knob of SolverFeatherstone; checked at each step.")
      .def(py::init<>())
      .def_readwrite("num_iterations", &Settings::num_iterations, "PGS sweeps per step.")
      .def_readwrite("linear_slop", &Settings::linear_slop, "Penetration (m) the position correction leaves alone.")
      .def_readwrite("erp", &Settings::erp, "Share of the penetration beyond the slop removed per step, in [0, 1].")
      .def_readwrite("cfm", &Settings::cfm, "Constraint force mixing: softens every constraint row.")
      .def_readwrite("pgs_tolerance", &Settings::pgs_tolerance,
                     "Stop the PGS sweeps once one sweep changed no row's velocity by more than this (m/s, "
                     "rad/s), per world; 0: once one sweep changed no impulse at all (a fixed point).")
      .def_readwrite("warmstarting_factor", &Settings::warmstarting_factor, "Share of last step's impulses reused.")
      .def_readwrite("restitution_threshold", &Settings::restitution_threshold, "Approach speed below which no bounce.")
      .def_readwrite("use_warmstarting", &Settings::use_warmstarting)
      .def_readwrite("angular_damping", &Settings::angular_damping,
                     "Rotational dof velocities are scaled by (1 - angular_damping * dt) each step.")
      .def_readwrite("update_mass_matrix_interval", &Settings::update_mass_matrix_interval,
                     "Recompute and refactor the mass matrix every N steps.")
      .def_readwrite("friction_smoothing", &Settings::friction_smoothing,
                     "0: box friction per tangent (direction snaps to the tangent axes); 1: circular cone "
                     "(friction opposes the slip direction smoothly); between: a blend.")
      .def_readwrite("use_tile_gemm", &Settings::use_tile_gemm, "Mass matrix as sum J^T I J instead of CRBA.")
      .def_readwrite("fuse_cholesky", &Settings::fuse_cholesky, "Factor and forward-substitute in one pass.")
      .def_readwrite("aba_min_dofs", &Settings::aba_min_dofs,
                     "Articulations with at least this many dofs use ABA (O(n), refactored every step) instead "
                     "of CRBA + Cholesky.")
      .def_readwrite("coriolis_implicitness", &Settings::coriolis_implicitness,
                     "0: explicit Coriolis forces; 0.5: linearised midpoint (energy kept to second order); 1: "
                     "linearised backward Euler. Above 0 the dense path with an LU each step, O(n^3).")
      .def_readwrite("weld_fixed_joints", &Settings::weld_fixed_joints,
                     "Merge bodies held by Fixed joints into their parent's link so they cost nothing in the dynamics "
                     "(read when the solver is made).")
      .def_readwrite("use_batch_kernels", &Settings::use_batch_kernels,
                     "Step articulations that share joints, frames and axes (replicated worlds) a SIMD block of "
                     "worlds at a time, in the model's precision; off: the scalar kernels for all.")
      .def_readwrite("stream_body_output_above", &Settings::stream_body_output_above,
                     "Write body_q and body_qd around the caches (non-temporal stores) when the step's data, the "
                     "state's arrays and the solver's, exceed this many bytes (0: always).")
      .def_readwrite("profile_stages", &Settings::profile_stages,
                     "Accumulate each stage's wall time into solver.stage_seconds; the batched blocks then run each "
                     "stage over all blocks in turn rather than a block's whole step at a time (same arithmetic).")
      .def_readwrite("num_threads", &Settings::num_threads,
                     "OpenMP threads over articulations (0: all available); results are bit-identical for any count.")
      .def_readwrite("on_divergence", &Settings::on_divergence,
                     "DivergencePolicy for an articulation whose state went non-finite or too fast.")
      .def_readwrite("divergence_speed", &Settings::divergence_speed,
                     "A dof speed (m/s, rad/s) beyond which an articulation counts as diverged.");

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

  py::class_<SolverFeatherstone>(m, "SolverFeatherstone",
                                 "Featherstone articulated-body solver: CRBA + Cholesky, sequential-impulse PGS.")
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
      .def("step", &SolverFeatherstone::step, py::arg("state_in"), py::arg("state_out"), py::arg("control"),
           py::arg("contacts"), py::arg("dt"), py::call_guard<py::gil_scoped_release>(),
           "Advances state_in by dt into state_out (they may be the same State).")
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
      .def_property_readonly("memory_bytes", &SolverFeatherstone::memory_bytes,
                             "Bytes the solver holds: batched blocks, scalar scratch, step vectors.")
      .def_property_readonly(
          "diverged",
          [](py::object self) {
            auto& flags = const_cast<std::vector<std::uint8_t>&>(self.cast<const SolverFeatherstone&>().diverged());
            return view(flags.data(), static_cast<int>(flags.size()), 1, self, false);
          },
          "Per articulation: 1 where the last step's divergence guard fired (a read-only view).");
}

}  // namespace novaphy::python
