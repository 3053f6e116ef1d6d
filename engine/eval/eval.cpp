#include "engine/eval/eval.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>

#include "engine/model/actuator.h"
#include "engine/model/body_kinematics.h"
#include "engine/model/error.h"
#include "engine/model/finite_checks.h"
#include "engine/model/spatial_tendon.h"
#include "engine/model/tendon.h"
#include "engine/solver/blocks/blocks.h"
#include "kernels/aba.h"
#include "kernels/cholesky.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/osim.h"
#include "kernels/rnea.h"

namespace novaphy {

namespace {

// the applied wrenches: the state's body_f, with what the model applies itself added where it has some (gravity
// compensation, a fluid's forces; the site actuators where a control is given) into `applied`
const Scalar* wrenches_of(const Model& model, ModelWrenches& wrenches, const State& state, const Control* control,
                          std::vector<Scalar>& applied) {
  if (!wrenches.any(control != nullptr)) return state.body_f.data();
  applied_wrenches(model, wrenches, state, control, applied);
  return applied.data();
}

// RNEA at qdd minus the passive joint forces: tau = H qdd + bias for one articulation, under the wrenches body_f
void articulation_inverse_dynamics(const State& state, const ArticulationView& art, ArticulationScratch& s,
                                   const Scalar* body_f, const Scalar* qdd, Scalar* tau) {
  rnea(art, qdd, art.gravity(), body_f, s, tau);
  VecX passive(art.dof_count());
  passive_force(art, state.joint_q.data() + art.q_begin(), state.joint_qd.data() + art.qd_begin(), passive.data());
  Eigen::Map<VecX>(tau, art.dof_count()) -= passive;
}

[[noreturn]] void fail_not_positive_definite(const Model& model, const ArticulationView& art, int dof) {
  int j = art.joint_begin;
  while (model.joint_qd_start[j + 1] <= art.qd_begin() + dof) ++j;
  fail("articulation ", model.joint_articulation[art.joint_begin], ": mass matrix is not positive definite at dof ",
       art.qd_begin() + dof, " (joint ", j, " '", model.joint_name[j], "'; a massless link without children?)");
}

}  // namespace

void eval_fk(const Model& model, State& state) {
  model.check(state);
  Checked arrays[] = {{&state.joint_q, "joint_q"}, {&state.joint_qd, "joint_qd"}};
  check_finite(arrays, 2, 1);
  bodies_from_joints(model, state);
}

MatX eval_mass_matrix(const Model& model, const State& state) {
  model.check(state);
  check_finite_state(state);
  MatX H = MatX::Zero(model.joint_dof_count, model.joint_dof_count);
  ArticulationScratch s;
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = kinematics(model, state, a, s);
    crba(art, s);
    H.block(art.qd_begin(), art.qd_begin(), art.dof_count(), art.dof_count()) = s.H;
  }
  return H;
}

Scalar eval_energy(const Model& model, const State& state) {
  const VecX qd = Eigen::Map<const VecX>(state.joint_qd.data(), model.joint_dof_count);
  Scalar e = 0.5 * qd.dot(eval_mass_matrix(model, state) * qd);
  for (int b = 0; b < model.body_count; ++b) {
    const Transform X = Transform::from_array(&state.body_q[7 * b]);
    const Vec3 g = Eigen::Map<const Vec3>(&model.world_gravity[3 * model.body_world[b]]);
    e -= model.body_mass[b] * g.dot(X.p + X.q * Eigen::Map<const Vec3>(&model.body_com[3 * b]));
  }
  return e;
}

VecX eval_bias_forces(const Model& model, const State& state) {
  return eval_inverse_dynamics(model, state, VecX::Zero(model.joint_dof_count));
}

VecX eval_inverse_dynamics(const Model& model, const State& state, const VecX& qdd) {
  model.check(state);
  check_finite_state(state);
  if (qdd.size() != model.joint_dof_count)
    fail("qdd has ", qdd.size(), " entries, the model has ", model.joint_dof_count, " dofs");
  for (Eigen::Index k = 0; k < qdd.size(); ++k)
    if (!std::isfinite(qdd[k])) fail("qdd[", k, "] is not finite: ", qdd[k]);
  VecX tau(model.joint_dof_count);
  ArticulationScratch s;
  std::vector<Scalar> applied;
  ModelWrenches wrenches = ModelWrenches::of(model);
  const Scalar* body_f = wrenches_of(model, wrenches, state, nullptr, applied);
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = kinematics(model, state, a, s);
    articulation_inverse_dynamics(state, art, s, body_f, qdd.data() + art.qd_begin(), tau.data() + art.qd_begin());
  }
  return tau;
}

void control_force(const Model& model, const Control& control, const State* state, Scalar* tau) {
  std::copy(control.joint_f.begin(), control.joint_f.end(), tau);
  auto needs_state = [&](int u) {
    if (!state && (model.actuator_bias[3 * u + 1] != 0 || model.actuator_bias[3 * u + 2] != 0))
      fail("actuator ", u, " '", model.actuator_name[u],
           "' depends on its joint's or tendon's position or velocity: its force needs the state "
           "(eval_control_force(model, control, state))");
  };
  for (int u = 0; u < model.actuator_count; ++u) {
    const int j = model.actuator_joint[u];
    if (j < 0) continue;
    needs_state(u);
    const int dof = model.joint_qd_start[j];
    const Scalar q = state ? state->joint_q[model.joint_q_start[j]] : 0, qd = state ? state->joint_qd[dof] : 0;
    tau[dof] += actuator_joint_force(model, u, control.actuator_ctrl[u], q, qd);
  }
  // fixed tendons (engine/model/tendon.h): their springs and dampers with the state, the actuators on them (a spatial
  // tendon's forces are wrenches on its bodies: applied_wrenches)
  for (int t = 0; t < model.tendon_count; ++t) {
    if (is_spatial(model, t)) continue;
    const Scalar length = state ? tendon_length(model, t, state->joint_q.data()) : 0;
    const Scalar velocity = state ? tendon_velocity(model, t, state->joint_qd.data()) : 0;
    Scalar force = state ? tendon_passive_force(model, t, length, velocity) : 0;
    for (int u = 0; u < model.actuator_count; ++u)
      if (model.actuator_tendon[u] == t) {
        needs_state(u);
        force += actuator_joint_force(model, u, control.actuator_ctrl[u], length, velocity);
      }
    add_tendon_force(model, t, force, tau);
  }
}

VecX eval_control_force(const Model& model, const Control& control, const State* state) {
  model.check(control);
  check_finite_control(control);
  if (state) {
    model.check(*state);
    check_finite_state(*state);
  }
  VecX tau(model.joint_dof_count);
  control_force(model, control, state, tau.data());
  return tau;
}

ForwardDynamics::ForwardDynamics(const Model& model)
    : model_(model), wrenches_(ModelWrenches::of(model)), tau_(model.joint_dof_count) {
  std::vector<std::uint8_t> batched(model.articulation_count);
  for (int a = 0; a < model.articulation_count; ++a) {
    articulations_.push_back(model.articulation(a));
    batched[a] = articulations_.back().dof_count() > 0;
  }
  batches_ = ArticulationBatches::make(model, articulations_, batched,
                                       std::vector<std::vector<WeldedBody>>(model.articulation_count), model.body_com,
                                       std::vector<int>(model.joint_dof_count, -1), model.precision);
  failure_.assign(model.articulation_count, -1);
}

ForwardDynamics::~ForwardDynamics() = default;

// the batched kernels' unconstrained step with dt = 0 and no drives
void ForwardDynamics::evaluate(const State& state, const Control& control, Scalar* qdd) {
  model_.check(state);
  model_.check(control);
  bool wrenches = false;
  check_finite_state(state, &wrenches);
  check_finite_control(control);
  control_force(model_, control, &state, tau_.data());
  std::fill_n(qdd, model_.joint_dof_count, Scalar(0));
  std::fill(failure_.begin(), failure_.end(), -1);
  const Scalar* body_f = wrenches_of(model_, wrenches_, state, &control, applied_body_f_);
  batches_->accelerations(state, control, tau_.data(), body_f, wrenches || body_f != state.body_f.data(), qdd,
                          failure_.data());
  for (int a = 0; a < model_.articulation_count; ++a)
    if (failure_[a] >= 0)
      fail_not_positive_definite(model_, articulations_[a], failure_[a] - articulations_[a].qd_begin());
}

VecX eval_forward_dynamics(const Model& model, const State& state, const Control& control,
                           ForwardDynamicsMethod method) {
  if (method == ForwardDynamicsMethod::Batched) {
    VecX qdd(model.joint_dof_count);
    ForwardDynamics(model).evaluate(state, control, qdd.data());
    return qdd;
  }
  model.check(state);
  check_finite_state(state);
  const VecX tau_control = eval_control_force(model, control, &state);
  VecX qdd(model.joint_dof_count);
  ArticulationScratch s;
  std::vector<Scalar> applied;
  ModelWrenches wrenches = ModelWrenches::of(model);
  const Scalar* body_f = wrenches_of(model, wrenches, state, &control, applied);
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = kinematics(model, state, a, s);
    const int nv = art.dof_count();
    Scalar* qdd_a = qdd.data() + art.qd_begin();
    const auto tau = tau_control.segment(art.qd_begin(), nv);
    if (method == ForwardDynamicsMethod::Crba) {
      const VecX zero = VecX::Zero(nv);
      articulation_inverse_dynamics(state, art, s, body_f, zero.data(), qdd_a);
      Eigen::Map<VecX>(qdd_a, nv) = tau - Eigen::Map<VecX>(qdd_a, nv);
      crba(art, s);
      const int bad = cholesky_factor(s.H);
      if (bad >= 0) fail_not_positive_definite(model, art, bad);
      cholesky_solve(s.H, qdd_a);
    } else {
      VecX tau_total(nv);
      passive_force(art, state.joint_q.data() + art.q_begin(), state.joint_qd.data() + art.qd_begin(),
                    tau_total.data());
      tau_total += tau;
      const int bad = aba(art, tau_total.data(), art.gravity(), body_f, s, qdd_a);
      if (bad >= 0) fail_not_positive_definite(model, art, art.qd_start(bad));
    }
  }
  return qdd;
}

}  // namespace novaphy
