// The seed's free functions on lists of Joint/RigidBody, and the same on a Model and State.
// The GIL is released while the engine computes.
#include "engine/eval/eval.h"

#include "bindings/bindings.h"
#include "engine/eval/articulation_functions.h"

namespace novaphy::python {

namespace {

ForwardDynamicsMethod method_from_name(const std::string& name) {
  if (name == "crba") return ForwardDynamicsMethod::Crba;
  if (name == "aba") return ForwardDynamicsMethod::Aba;
  if (name == "batched") return ForwardDynamicsMethod::Batched;
  throw py::value_error("method must be 'crba', 'aba' or 'batched', got '" + name + "'");
}

// f(model, state) of a function that reads the state, on its double fields (Widened)
template <auto f>
auto reading_state(const Model& model, State& state) {
  const Widened<State> read(state, false);
  return f(model, state);
}

}  // namespace

void bind_eval(py::module_& m) {
  const auto release = py::call_guard<py::gil_scoped_release>();

  py::class_<Joint>(m, "Joint", "Joint of the free functions: joints[i] attaches link i to link parent (-1: world).")
      .def(py::init<>())
      .def_readwrite("type", &Joint::type)
      .def_readwrite("axis", &Joint::axis)
      .def_readwrite("parent", &Joint::parent)
      .def_readwrite("parent_to_joint", &Joint::parent_to_joint);

  m.def("forward_kinematics", &forward_kinematics, py::arg("joints"), py::arg("q"), release,
        "World transforms [px, py, pz, qx, qy, qz, qw] of every link, shape (n_links, 7).");
  m.def("inverse_dynamics", &inverse_dynamics, py::arg("joints"), py::arg("bodies"), py::arg("q"), py::arg("qd"),
        py::arg("qdd"), py::arg("gravity"), release, "Joint forces tau = H qdd + C qd + g (RNEA).");
  m.def("mass_matrix_crba", &mass_matrix_crba, py::arg("joints"), py::arg("bodies"), py::arg("q"), release,
        "Joint-space mass matrix H(q) (CRBA).");
  m.def("forward_dynamics", &forward_dynamics, py::arg("joints"), py::arg("bodies"), py::arg("q"), py::arg("qd"),
        py::arg("tau"), py::arg("gravity"), release, "Joint accelerations from H qdd = tau - C qd - g.");

  m.def(
      "eval_fk",
      [](const Model& model, State& state) {
        const Widened<State> written(state, true);
        eval_fk(model, state);
      },
      py::arg("model"), py::arg("state"), release,
      "Fills state.body_q and state.body_qd from state.joint_q and state.joint_qd.");
  m.def("eval_mass_matrix", &reading_state<eval_mass_matrix>, py::arg("model"), py::arg("state"), release,
        "Dense (joint_dof_count, joint_dof_count) mass matrix, block diagonal over articulations.");
  m.def("eval_energy", &reading_state<eval_energy>, py::arg("model"), py::arg("state"), release,
        "Kinetic energy 1/2 qd^T H qd plus the gravitational potential energy of every body's centre of mass, at "
        "state.body_q.");
  m.def("eval_bias_forces", &reading_state<eval_bias_forces>, py::arg("model"), py::arg("state"), release,
        "bias = C qd + g - tau_passive - J^T body_f, so that H qdd = tau - bias.");
  m.def(
      "eval_inverse_dynamics",
      [](const Model& model, State& state, const VecX& qdd) {
        const Widened<State> read(state, false);
        return eval_inverse_dynamics(model, state, qdd);
      },
      py::arg("model"), py::arg("state"), py::arg("qdd"), release, "tau = H qdd + bias (RNEA).");
  m.def(
      "eval_control_force",
      [](const Model& model, Control& control, State* state) {
        const Widened<Control> read(control, false);
        if (state) state->from_float32();
        return eval_control_force(model, control, state);
      },
      py::arg("model"), py::arg("control"), py::arg("state") = nullptr, release,
      "tau = control.joint_f plus every actuator's joint force at the state (needed where an actuator has a "
      "position or velocity term).");
  py::class_<ForwardDynamics>(m, "ForwardDynamics",
                              "Forward dynamics of one model evaluated again and again: the solver's batched kernels "
                              "(the model's precision) made once, so an evaluation sets nothing up.")
      .def(py::init<const Model&>(), py::arg("model"), py::keep_alive<1, 2>())
      .def(
          "evaluate",
          [](ForwardDynamics& self, State& state, Control& control) {
            VecX qdd(state.joint_qd.size());
            {
              py::gil_scoped_release unlocked;
              const Widened<State> read_state(state, false);
              const Widened<Control> read_control(control, false);
              self.evaluate(state, control, qdd.data());
            }
            return qdd;
          },
          py::arg("state"), py::arg("control"),
          "qdd as eval_forward_dynamics(model, state, control) gives it, on the batched kernels.");
  m.def(
      "eval_forward_dynamics",
      [](const Model& model, State& state, Control& control, const std::string& method) {
        const ForwardDynamicsMethod chosen = method_from_name(method);
        py::gil_scoped_release unlocked;
        const Widened<State> read_state(state, false);
        const Widened<Control> read_control(control, false);
        return eval_forward_dynamics(model, state, control, chosen);
      },
      py::arg("model"), py::arg("state"), py::arg("control"), py::kw_only(), py::arg("method") = "crba",
      "qdd from tau = eval_control_force(model, control): 'crba' (CRBA + Cholesky), 'aba' (articulated-body "
      "algorithm) or 'batched' (the solver's batched kernels, in the model's precision).");
}

}  // namespace novaphy::python
