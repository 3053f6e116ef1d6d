// Whole-model evaluations over every articulation (contacts and limits off): forward kinematics,
// mass matrix, bias forces, inverse and forward dynamics. The equations of motion are
//   H(q) qdd = tau - bias(q, qd),   bias = C(q, qd) qd + g(q) - tau_passive - J^T f_ext
// with f_ext the applied body wrenches state.body_f and tau_passive the joint damping and springs.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// Crba: CRBA + Cholesky; Aba: the articulated-body algorithm; Batched: the solver's batched kernels
// (kernels/batch.h) in the model's precision, each articulation a lane of its own block
enum class ForwardDynamicsMethod { Crba, Aba, Batched };

// state.body_q and state.body_qd from state.joint_q and state.joint_qd
void eval_fk(const Model& model, State& state);

// dense joint_dof_count x joint_dof_count matrix, block diagonal over articulations
MatX eval_mass_matrix(const Model& model, const State& state);
// model.body_invweight0 (model.h), MuJoCo's, from joint_q0: the builder's last step
void set_body_invweight0(Model& model);

VecX eval_bias_forces(const Model& model, const State& state);

// kinetic energy 1/2 qd^T H qd plus the potential energy of every body's centre of mass in gravity,
// at state.body_q (after eval_fk or a step)
Scalar eval_energy(const Model& model, const State& state);

// tau = H qdd + bias
VecX eval_inverse_dynamics(const Model& model, const State& state, const VecX& qdd);

// tau = control.joint_f plus every actuator's joint force (engine/solver/parts/actuator.h) at the state's coordinates
// and velocities, and with a state every tendon's spring and damper (engine/solver/parts/tendon.h); without a state
// (nullptr) every actuator must be free of position and velocity bias
VecX eval_control_force(const Model& model, const Control& control, const State* state = nullptr);
void control_force(const Model& model, const Control& control, const State* state, Scalar* tau);  // joint_dof_count

// body_q / body_qd of body b, riding on link `link` at `offset` (its pose in the link frame) with its
// centre of mass at `com` (body frame), from scratch after forward_kinematics + forward_velocity
void store_body(const ArticulationScratch& s, int link, const Transform& offset, const Vec3& com, int b, State& state);
// store_body for every link body of the articulation
void store_body_state(const ArticulationView& art, const ArticulationScratch& s, State& state);

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
  std::vector<Scalar> tau_;
  std::vector<int> failure_;
};

// one pass over the bits of x[begin, end): ORs into *bad a nonzero where an entry is inf or NaN (an exponent of all
// ones) and into *nonzero one where an entry is not +-0 (any bit but the sign's); vectorises
inline void scan_bits(const Scalar* x, long begin, long end, std::uint64_t* bad, std::uint64_t* nonzero) {
  static_assert(sizeof(Scalar) == sizeof(std::uint64_t));
  constexpr std::uint64_t kExponent = 0x7ff0000000000000;
  std::uint64_t b = 0, any = 0;
  for (long k = begin; k < end; ++k) {
    std::uint64_t bits;
    std::memcpy(&bits, &x[k], sizeof(bits));
    b |= (bits & kExponent) == kExponent;
    any |= bits << 1;
  }
  *bad |= b;
  *nonzero |= any;
}

// throws Error naming the first non-finite entry of state.joint_q / joint_qd / body_f; any_wrench
// (when given) is set to whether body_f holds a nonzero entry
void check_finite_state(const State& state, bool* any_wrench = nullptr, int threads = 1);
// throws Error naming the first non-finite entry of any control array
// any_drive (when given) is set to whether a PD gain (joint_target_ke or joint_target_kd) is nonzero
void check_finite_control(const Control& control, bool* any_drive = nullptr, int threads = 1);
// both, in that order, in one pass (one parallel region on `threads` threads), except the PD targets
// (joint_target_pos, joint_target_vel): a step reads them only where a gain is nonzero, so they are checked
// only when any_drive is set, in a second pass
void check_finite_step(const State& state, const Control& control, bool* any_wrench, bool* any_drive, int threads = 1);

}  // namespace novaphy
