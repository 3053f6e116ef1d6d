#include "engine/eval/eval.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>

#include "engine/model/error.h"
#include "engine/solver/blocks/blocks.h"
#include "engine/solver/parts/actuator.h"
#include "engine/solver/parts/tendon.h"
#include "kernels/aba.h"
#include "kernels/cholesky.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/osim.h"
#include "kernels/rnea.h"

namespace novaphy {

namespace {

// arrays checked together: each one's name and, after the check, whether it has a nonzero entry
struct Checked {
  const std::vector<Scalar>* x = nullptr;
  const char* name = nullptr;
  bool nonzero = false;
};
constexpr int kMostChecked = 16;

// throws Error naming the first non-finite entry of the first array (in order) that has one; sets each
// array's nonzero. One pass over the bits (an exponent of all ones is inf or NaN; any bit but the
// sign's, a nonzero), vectorised; on `threads` threads when the arrays are long, all of them in one
// parallel region (each thread its share of every array); the search only on failure
void check_finite(Checked* arrays, int count, int threads) {
  std::uint64_t not_finite[kMostChecked] = {}, nonzero[kMostChecked] = {};
  auto scan = [&](int t, int teams) {
    for (int a = 0; a < count; ++a) {
      const std::vector<Scalar>& x = *arrays[a].x;
      const long n = static_cast<long>(x.size());
      std::uint64_t bad = 0, any = 0;
      scan_bits(x.data(), n * t / teams, n * (t + 1) / teams, &bad, &any);
      if (teams == 1) {
        not_finite[a] = bad;
        nonzero[a] = any;
        continue;
      }
#pragma omp atomic
      not_finite[a] |= bad;
#pragma omp atomic
      nonzero[a] |= any;
    }
  };
  long total = 0;
  for (int a = 0; a < count; ++a) total += static_cast<long>(arrays[a].x->size());
  if (threads > 1 && total >= 65536) {  // (a parallel region costs short arrays more than their scan)
#pragma omp parallel num_threads(threads)
    scan(omp_get_thread_num(), omp_get_num_threads());
  } else {
    scan(0, 1);
  }
  for (int a = 0; a < count; ++a) {
    arrays[a].nonzero = nonzero[a] != 0;
    if (not_finite[a] == 0) continue;
    const std::vector<Scalar>& x = *arrays[a].x;
    for (size_t k = 0; k < x.size(); ++k)
      if (!std::isfinite(x[k])) fail(arrays[a].name, "[", k, "] is not finite: ", x[k]);
  }
}

// the state's arrays (body_f at kBodyF), then the control's, into `arrays` from `count`; each returns the
// new count
constexpr int kBodyF = 2;
int state_arrays(const State& state, Checked* arrays, int count) {
  arrays[count++] = {&state.joint_q, "joint_q"};
  arrays[count++] = {&state.joint_qd, "joint_qd"};
  arrays[count++] = {&state.body_f, "body_f"};
  return count;
}
int control_arrays(const Control& control, Checked* arrays, int count) {
#define NOVAPHY_CHECKED_CONTROL(T, name, n, width) arrays[count++] = {&control.name, #name};
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_CHECKED_CONTROL)
#undef NOVAPHY_CHECKED_CONTROL
  return count;
}
// whether a PD gain (joint_target_ke or joint_target_kd) is nonzero, among checked arrays
bool any_drive(const Control& control, const Checked* arrays, int count) {
  bool drive = false;
  for (int a = 0; a < count; ++a)
    drive |= (arrays[a].x == &control.joint_target_ke || arrays[a].x == &control.joint_target_kd) && arrays[a].nonzero;
  return drive;
}

// FK and link velocities of articulation a at the state's coordinates
ArticulationView kinematics(const Model& model, const State& state, int a, ArticulationScratch& s) {
  const ArticulationView art = model.articulation(a);
  s.resize(art);
  forward_kinematics(art, state.joint_q.data() + art.q_begin(), s);
  forward_velocity(art, state.joint_qd.data() + art.qd_begin(), s);
  return art;
}

// RNEA at qdd minus the passive joint forces: tau = H qdd + bias for one articulation
void articulation_inverse_dynamics(const Model& model, const State& state, const ArticulationView& art,
                                   ArticulationScratch& s, const Scalar* qdd, Scalar* tau) {
  rnea(art, qdd, model.gravity, state.body_f.data(), s, tau);
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

// the bytes that decide an articulation's body_invweight0 (joint_q0's FK, the articulated-body factor and
// osim_inverse) into key: per link its joint's type, parent and frames, axis, q0, armature and its body's mass, COM
// and inertia; not a root's parent frame nor a root Free joint's position, which only place the articulation in the
// world: neither enters a root's S or articulated inertia, and osim_inverse reads no transform above a root (so
// replicas placed apart share one key, their weights the same bits)
void invweight0_key(const Model& model, const ArticulationView& art, std::string& key) {
  key.clear();
  auto put = [&](const auto* x, int count) { key.append(reinterpret_cast<const char*>(x), sizeof(*x) * count); };
  for (int i = 0; i < art.link_count(); ++i) {
    const int j = art.joint_begin + i, b = art.body(i), parent = art.parent(i);
    const int skip = parent < 0 && art.type(i) == JointType::Free ? 3 : 0;  // (a root Free joint's position)
    put(&model.joint_type[j], 1);
    put(&parent, 1);
    if (parent >= 0) put(&model.joint_X_p[7 * j], 7);
    put(&model.joint_X_c[7 * j], 7);
    put(&model.joint_axis[3 * j], 3);
    put(model.joint_q0.data() + model.joint_q_start[j] + skip, joint_coord_count(art.type(i)) - skip);
    put(model.joint_armature.data() + model.joint_qd_start[j], art.dof(i));
    put(&model.body_mass[b], 1);
    put(&model.body_com[3 * b], 3);
    put(&model.body_inertia[9 * b], 9);
  }
}

}  // namespace

void check_finite_state(const State& state, bool* any_wrench, int threads) {
  Checked arrays[kMostChecked];
  const int count = state_arrays(state, arrays, 0);
  check_finite(arrays, count, threads);
  if (any_wrench) *any_wrench = arrays[kBodyF].nonzero;
}

void check_finite_control(const Control& control, bool* any_drive_out, int threads) {
  Checked arrays[kMostChecked];
  const int count = control_arrays(control, arrays, 0);
  check_finite(arrays, count, threads);
  if (any_drive_out) *any_drive_out = any_drive(control, arrays, count);
}

void check_finite_step(const State& state, const Control& control, bool* any_wrench, bool* any_drive_out, int threads) {
  Checked all[kMostChecked], arrays[kMostChecked], targets[kMostChecked];
  const int total = control_arrays(control, all, state_arrays(state, all, 0));
  int count = 0, target_count = 0;
  for (int a = 0; a < total; ++a) {
    const bool target = all[a].x == &control.joint_target_pos || all[a].x == &control.joint_target_vel;
    (target ? targets[target_count++] : arrays[count++]) = all[a];
  }
  check_finite(arrays, count, threads);
  *any_wrench = arrays[kBodyF].nonzero;
  *any_drive_out = any_drive(control, arrays, count);
  if (*any_drive_out) check_finite(targets, target_count, threads);
}

void store_body(const ArticulationScratch& s, int link, const Transform& offset, const Vec3& com, int b, State& state) {
  const Transform& X = s.X_world[link];
  (X * offset).to_array(state.body_q.data() + 7 * b);
  // body_qd = [velocity of the centre of mass; angular velocity], world frame
  const Vec3 w = s.v[link].head<3>();
  const Vec3 v_com = s.v[link].tail<3>() + w.cross(offset.apply(com));
  const Mat3 R = X.rotation();
  Eigen::Map<Vec6>(state.body_qd.data() + 6 * b) << R * v_com, R * w;
}

void store_body_state(const ArticulationView& art, const ArticulationScratch& s, State& state) {
  for (int i = 0; i < art.link_count(); ++i) store_body(s, i, Transform::identity(), art.com(i), art.body(i), state);
}

void eval_fk(const Model& model, State& state) {
  model.check(state);
  Checked arrays[] = {{&state.joint_q, "joint_q"}, {&state.joint_qd, "joint_qd"}};
  check_finite(arrays, 2, 1);
  ArticulationScratch s;
  for (int a = 0; a < model.articulation_count; ++a) store_body_state(kinematics(model, state, a, s), s, state);
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

void set_body_invweight0(Model& model) {
  // inputs: the model at joint_q0; outputs: body_invweight0 (0 for a static body)
  model.body_invweight0.assign(2 * static_cast<size_t>(model.body_count), 0);
  ArticulationScratch s;
  std::vector<Mat6> Omega;
  std::unordered_map<std::string, int> computed;  // an articulation's defining data -> the first that has it
  std::string key;
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = model.articulation(a);
    if (art.dof_count() == 0) continue;  // (welded to the world: weightless, as MuJoCo's static bodies)
    // a replica of one already computed: the same weights, link by link
    invweight0_key(model, art, key);
    const auto [first, inserted] = computed.try_emplace(key, a);
    if (!inserted) {
      const ArticulationView same = model.articulation(first->second);
      for (int i = 0; i < art.link_count(); ++i)
        std::copy_n(&model.body_invweight0[2 * same.body(i)], 2, &model.body_invweight0[2 * art.body(i)]);
      continue;
    }
    s.resize(art);
    forward_kinematics(art, model.joint_q0.data() + art.q_begin(), s);
    if (osim_inverse(art, s, Omega) >= 0) continue;
    for (int i = 0; i < art.link_count(); ++i) {
      // the COM's velocity v + w x c = v - [c]x w: C = [-[c]x, 1] maps the link's [w; v] to it
      Eigen::Matrix<Scalar, 3, 6> C;
      C << -skew(art.com(i)), Mat3::Identity();
      const int b = art.body(i);
      model.body_invweight0[2 * b] = (C * Omega[i] * C.transpose()).trace() / 3;
      model.body_invweight0[2 * b + 1] = Omega[i].topLeftCorner<3, 3>().trace() / 3;
    }
  }
}

Scalar eval_energy(const Model& model, const State& state) {
  const VecX qd = Eigen::Map<const VecX>(state.joint_qd.data(), model.joint_dof_count);
  Scalar e = 0.5 * qd.dot(eval_mass_matrix(model, state) * qd);
  for (int b = 0; b < model.body_count; ++b) {
    const Transform X = Transform::from_array(&state.body_q[7 * b]);
    e -= model.body_mass[b] * model.gravity.dot(X.p + X.q * Eigen::Map<const Vec3>(&model.body_com[3 * b]));
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
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = kinematics(model, state, a, s);
    articulation_inverse_dynamics(model, state, art, s, qdd.data() + art.qd_begin(), tau.data() + art.qd_begin());
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
  // tendons (engine/solver/parts/tendon.h): their springs and dampers with the state, the actuators on them
  for (int t = 0; t < model.tendon_count; ++t) {
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

ForwardDynamics::ForwardDynamics(const Model& model) : model_(model), tau_(model.joint_dof_count) {
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
  batches_->accelerations(state, control, tau_.data(), wrenches, qdd, failure_.data());
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
  for (int a = 0; a < model.articulation_count; ++a) {
    const ArticulationView art = kinematics(model, state, a, s);
    const int nv = art.dof_count();
    Scalar* qdd_a = qdd.data() + art.qd_begin();
    const auto tau = tau_control.segment(art.qd_begin(), nv);
    if (method == ForwardDynamicsMethod::Crba) {
      const VecX zero = VecX::Zero(nv);
      articulation_inverse_dynamics(model, state, art, s, zero.data(), qdd_a);
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
      const int bad = aba(art, tau_total.data(), model.gravity, state.body_f.data(), s, qdd_a);
      if (bad >= 0) fail_not_positive_definite(model, art, art.qd_start(bad));
    }
  }
  return qdd;
}

}  // namespace novaphy
