// Whole-model evaluations over every articulation (contacts and limits off): forward kinematics,
// mass matrix, bias forces, inverse and forward dynamics. The equations of motion are
//   H(q) qdd = tau - bias(q, qd),   bias = C(q, qd) qd + g(q) - tau_passive - J^T f_ext
// with f_ext the applied body wrenches state.body_f (and what the model applies itself: gravity compensation, and in
// forward dynamics its actuators on sites) and tau_passive the joint damping and springs.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "engine/model/finite_checks.h"
#include "engine/model/model.h"
#include "engine/solver/parts/applied_wrenches.h"

namespace novaphy {

// Crba: CRBA + Cholesky; Aba: the articulated-body algorithm; Batched: the solver's batched kernels
// (kernels/batch.h) in the model's precision, each articulation a lane of its own block
enum class ForwardDynamicsMethod { Crba, Aba, Batched };

// state.body_q and state.body_qd from state.joint_q and state.joint_qd
void eval_fk(const Model& model, State& state);

// dense joint_dof_count x joint_dof_count matrix, block diagonal over articulations
MatX eval_mass_matrix(const Model& model, const State& state);
VecX eval_bias_forces(const Model& model, const State& state);

// kinetic energy 1/2 qd^T H qd plus the potential energy of every body's centre of mass in gravity,
// at state.body_q (after eval_fk or a step)
Scalar eval_energy(const Model& model, const State& state);

// tau = H qdd + bias
VecX eval_inverse_dynamics(const Model& model, const State& state, const VecX& qdd);

// tau = control.joint_f plus every actuator's joint force (engine/model/actuator.h) at the state's coordinates
// and velocities, and with a state every fixed tendon's spring and damper (engine/model/tendon.h); without a state
// (nullptr) every actuator must be free of position and velocity bias. A spatial tendon's spring, damper and
// actuators pull its bodies (wrenches, engine/solver/parts/applied_wrenches.h): not in tau, in the dynamics' body_f
VecX eval_control_force(const Model& model, const Control& control, const State* state = nullptr);
void control_force(const Model& model, const Control& control, const State* state, Scalar* tau);  // joint_dof_count

// qdd from tau = eval_control_force(model, control); CRBA + Cholesky or ABA
VecX eval_forward_dynamics(const Model& model, const State& state, const Control& control,
                           ForwardDynamicsMethod method = ForwardDynamicsMethod::Crba);

class ArticulationBatches;

// Forward dynamics of one model evaluated again and again (a controller's model of one robot, or many): the
// batched kernels of the solver's step (each articulation a lane of its block, in the model's precision) are made
// once here, so an evaluation does no set-up and allocates nothing. The model must outlive it, unchanged.
class ForwardDynamics {
 public:
  explicit ForwardDynamics(const Model& model);
  ~ForwardDynamics();
  ForwardDynamics(const ForwardDynamics&) = delete;
  ForwardDynamics& operator=(const ForwardDynamics&) = delete;
  // qdd [joint_dof_count] from tau = eval_control_force(model, control, &state), checked as eval_forward_dynamics
  // checks its arguments
  void evaluate(const State& state, const Control& control, Scalar* qdd);

 private:
  const Model& model_;
  std::vector<ArticulationView> articulations_;
  std::unique_ptr<ArticulationBatches> batches_;
  ModelWrenches wrenches_;  // what the model applies itself
  std::vector<Scalar> tau_;
  std::vector<Scalar> applied_body_f_;  // body_f with what the model applies itself, where it has some
  std::vector<int> failure_;
};

}  // namespace novaphy
