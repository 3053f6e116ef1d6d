// The Dynamics stage of one block: forward kinematics, bias forces with the applied wrenches, the
// implicit dampers, springs and drives (engine/solver/parts/drive.h), H and its factor, the unconstrained velocity.
#include <type_traits>

#include "engine/solver/blocks/block_data.h"
#include "engine/solver/parts/drive.h"
#include "engine/solver/parts/wrench.h"
#include "kernels/batch/lane_math.h"

namespace novaphy {

namespace {

using namespace lane_math;

// applied wrenches [f at the centre of mass; torque] of the block's bodies (welded ones onto their
// links) as spatial forces about o into w.f_ext; false when the block has none
template <typename T>
bool gather_wrenches(const BatchGroup<T>& G, int b, const Scalar* body_f, const Lanes<T>* o, BatchWork<T>& w) {
  using V = Lanes<T>;
  constexpr int W = kLanes<T>;
  const int n = G.links(), nb = G.bodies();
  const int* body = &G.body[static_cast<size_t>(b) * W * nb];
  bool any = false;
  for (int k = 0; k < W * nb; ++k)
    for (int m = 0; m < 6; ++m) any |= body_f[6 * body[k] + m] != 0;
  if (!any) return false;
  std::fill(w.f_ext.begin(), w.f_ext.end(), V{});
  const V* body_com = G.body_com(b);
  for (int k = 0; k < nb; ++k) {
    const int link = k < n ? k : G.welds[k - n].link;
    V f[6], c[3], p[3], Q[4];
    for (int l = 0; l < W; ++l)
      for (int m = 0; m < 6; ++m) f[m][l] = static_cast<T>(body_f[6 * body[l * nb + k] + m]);
    if (k < n) {
      body_point<T>(&w.p[3 * k], &w.Q[4 * k], body_com + 3 * k, o, c);
    } else {
      weld_pose<T>(G.welds[k - n], w, p, Q);
      body_point<T>(p, Q, body_com + 3 * k, o, c);
    }
    V* F = &w.f_ext[6 * link];
    add_wrench_about(f, f + 3, c, F, F + 3);
  }
  return true;
}

// x = tau - bias and the implicit terms of every dof, w.diag their diagonal
template <typename T>
void add_joint_forces(const BatchGroup<T>& G, int b, const BatchParams<T>& P, const StepContext& step,
                      const UnitInputs& inputs, BatchWork<T>& w) {
  using V = Lanes<T>;
  const int nv = G.topo.dof_count;
  const int* qd_off = &G.qd_off[static_cast<size_t>(b) * kLanes<T>];
  V* x = w.x.data();
  gather_lanes<T>(qd_off, step.tau, nv, x);
  // the PD drives' gains and targets (the targets are read only where some gain is nonzero), the actuators'
  // stiffness and damping
  V *kd = w.kd.data(), *vt = w.target_vel.data(), *ke = w.ke.data(), *qt = w.target_pos.data();
  V *ka = w.actuator_stiffness.data(), *da = w.actuator_damping.data();
  if (inputs.drives) {
    const Control& control = *step.control;
    gather_lanes<T>(qd_off, control.joint_target_kd.data(), nv, kd);
    gather_lanes<T>(qd_off, control.joint_target_vel.data(), nv, vt);
    gather_lanes<T>(qd_off, control.joint_target_ke.data(), nv, ke);
    gather_lanes<T>(qd_off, control.joint_target_pos.data(), nv, qt);
  } else {
    for (V* gains : {kd, vt, ke, qt}) std::fill(gains, gains + nv, V{});
  }
  const V dt = splat<V>(static_cast<T>(step.dt));
  for (int k = 0; k < nv; ++k) {
    const DofDrive<V> d{P.damping[k], kd[k], vt[k], P.stiffness[k], P.q_ref[k], ke[k], qt[k]};
    const int c = G.topo.coord_of_dof[k];
    w.diag[k] = add_dof_forces(d, w.tau[k], w.qd[k], c < 0 ? nullptr : &w.q[c], dt, x[k]);
  }
  if (!inputs.actuator_stiffness) return;
  gather_lanes<T>(qd_off, inputs.actuator_stiffness, nv, ka);
  gather_lanes<T>(qd_off, inputs.actuator_damping, nv, da);
  for (int k = 0; k < nv; ++k) {
    const int c = G.topo.coord_of_dof[k];  // (actuators drive Revolute and Prismatic joints only)
    if (c >= 0) w.diag[k] += add_actuator_forces(ka[k], da[k], w.q[c], w.qd[k], dt, x[k]);
  }
}

// x * s computed in double and rounded to T: what a lane of T stored to a double and scaled becomes
template <typename T>
Lanes<T> scale_in_double(const Lanes<T>& x, Scalar s) {
  if constexpr (std::is_same_v<T, double>) {
    return x * s;
  } else {
    typedef double Wide __attribute__((vector_size(kLanes<T> * sizeof(double))));
    return __builtin_convertvector(__builtin_convertvector(x, Wide) * s, Lanes<T>);
  }
}

}  // namespace

template <typename T>
void block_dynamics(BatchGroup<T>& G, int b, const BlockKinematics<T>& kin, const StepContext& step,
                    const UnitInputs& inputs, BatchWork<T>& w, bool carry_on, Scalar* qdd) {
  using V = Lanes<T>;
  constexpr int W = kLanes<T>;
  const BatchTopology<T>& topo = G.topo;
  const int nv = topo.dof_count;
  const int* qd_off = &G.qd_off[b * W];
  gather_lanes<T>(&G.q_off[b * W], step.in->joint_q.data(), topo.coord_count, w.q.data());
  gather_lanes<T>(qd_off, step.in->joint_qd.data(), nv, w.qd.data());
  const BatchParams<T> P = G.block_params(b);
  batch_kinematics(topo, w.q.data(), w, kin.o);
  batch_subspace(topo, w, kin.o, kin.S);
  batch_velocity(topo, kin.S, w.qd.data(), w);
  batch_link_inertia(topo, P, kin.o, w);
  const bool pushed = inputs.wrenches && gather_wrenches(G, b, step.body_f, kin.o, w);
  batch_bias(topo, kin.S, P.gravity, pushed ? w.f_ext.data() : nullptr, w, w.tau.data());
  add_joint_forces(G, b, P, step, inputs, w);

  V* x = w.x.data();
  IntLanes<T> bad = IntLanes<T>{} - 1;
  if (G.refactor) {
    if (step.settings.use_tile_gemm)
      batch_mass_matrix_gemm(topo, P, kin.S, w, kin.H);
    else
      batch_mass_matrix(topo, P, kin.S, w, kin.H);
    for (int k = 0; k < nv; ++k) kin.H[topo.row_start[k] + k] += w.diag[k];
    bad = batch_factor(topo, kin.H, step.settings.fuse_cholesky ? x : nullptr);
    if (step.settings.fuse_cholesky)
      batch_solve_lower(topo, kin.H, x);
    else
      batch_solve(topo, kin.H, x);
  } else {
    batch_solve(topo, kin.H, x);
  }
  for (int l = 0; l < G.lanes_in(b); ++l) {
    if (bad[l] >= 0) step.factor_failure[G.arts[b * W + l]] = qd_off[l] + static_cast<int>(bad[l]);
    if (qdd)
      for (int k = 0; k < nv; ++k) qdd[qd_off[l] + k] = x[k][l];
  }
  if (qdd) return;
  // the new velocities, a rotational dof's scaled in double and rounded to T
  for (int k = 0; k < nv; ++k) w.qd[k] = w.qd[k] + static_cast<T>(step.dt) * x[k];
  for (const int k : G.rotational) w.qd[k] = scale_in_double<T>(w.qd[k], step.keep);
  if (!carry_on) scatter_lanes<T>(qd_off, w.qd.data(), nv, real_lanes(G, b), step.qd);
}

template void block_dynamics(BatchGroup<float>&, int, const BlockKinematics<float>&, const StepContext&,
                             const UnitInputs&, BatchWork<float>&, bool, Scalar*);
template void block_dynamics(BatchGroup<double>&, int, const BlockKinematics<double>&, const StepContext&,
                             const UnitInputs&, BatchWork<double>&, bool, Scalar*);

}  // namespace novaphy
