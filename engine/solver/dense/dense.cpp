#include "engine/solver/dense/dense.h"

#include <algorithm>

#include "engine/model/body_kinematics.h"
#include "engine/solver/parts/drive.h"
#include "engine/solver/parts/guard.h"
#include "engine/solver/parts/rows.h"
#include "engine/solver/parts/wrench.h"
#include "kernels/aba.h"
#include "kernels/cholesky.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/integrate.h"
#include "kernels/rnea.h"

namespace novaphy {

DenseArticulations::DenseArticulations(const Model& model, const std::vector<ArticulationView>& art,
                                       const std::vector<std::vector<WeldedBody>>& welded)
    : model_(model), art_(art), welded_(welded) {
  const size_t n = art.size();
  scratch_.resize(n);
  factor_.assign(n, Factor::None);
  constant_mass_.assign(n, 0);
  constant_H_.resize(n);
  factored_diagonal_.resize(n);
  implicit_lu_.resize(n);
  rotational_.resize(n);
  for (size_t a = 0; a < n; ++a) {
    bool constant = art[a].dof_count() > 0;
    for (int i = 0; i < art[a].link_count(); ++i) {
      const JointType type = art[a].type(i);
      constant &= type == JointType::Prismatic || type == JointType::Fixed;
      if (type == JointType::Revolute) rotational_[a].push_back(art[a].qd_start(i));
      if (type == JointType::Ball || type == JointType::Free)
        for (int k = 0; k < 3; ++k) rotational_[a].push_back(art[a].qd_start(i) + k);
    }
    constant_mass_[a] = constant;
  }
  rhs_.assign(model.joint_dof_count, 0);
  for (size_t a = 0; a < n; ++a)
    if (!welded[a].empty()) link_f_.assign(6 * static_cast<size_t>(model.body_count), 0);
}

void DenseArticulations::assign(const std::vector<int>& articulations) {
  units_ = articulations;
  for (const int a : units_) {
    factor_[a] = Factor::None;
    factored_diagonal_[a].resize(0);
  }
}

ArticulationScratch& DenseArticulations::scratch(int a) {
  if (scratch_[a].X_up.empty()) scratch_[a].resize(art_[a]);
  return scratch_[a];
}

void DenseArticulations::joint_forces(int a, const StepContext& step, const UnitInputs& inputs, Scalar* rhs,
                                      VecX& diagonal) {
  const ArticulationView& art = art_[a];
  ArticulationScratch& s = scratch_[a];
  const int q0 = art.q_begin(), qd0 = art.qd_begin();
  const Scalar* q = step.in->joint_q.data() + q0;
  const Scalar* qd = step.in->joint_qd.data() + qd0;
  const Control& control = *step.control;
  VecX& bias = s.tau_step;
  bias.resize(art.dof_count());
  rnea(art, s.qdd_zero.data(), art.gravity(), link_wrenches(a, step.body_f), s, bias.data());
  for (int i = 0; i < art.link_count(); ++i) {
    const bool coordinate = art.type(i) == JointType::Revolute || art.type(i) == JointType::Prismatic;
    for (int m = 0; m < art.dof(i); ++m) {
      const int k = art.qd_start(i) + m, g = qd0 + k;
      // (the targets are read only when some gain is nonzero: unchecked otherwise)
      const Scalar target_vel = inputs.drives ? control.joint_target_vel[g] : 0;
      const Scalar target_pos = inputs.drives ? control.joint_target_pos[g] : 0;
      const Scalar q_ref = coordinate ? model_.joint_q_ref[q0 + art.q_start(i)] : 0;
      const DofDrive<Scalar> d{model_.joint_damping[g],
                               control.joint_target_kd[g],
                               target_vel,
                               model_.joint_stiffness[g],
                               q_ref,
                               control.joint_target_ke[g],
                               target_pos};
      rhs[k] = step.tau[g];
      diagonal[k] = add_dof_forces(d, bias[k], qd[k], coordinate ? q + art.q_start(i) : nullptr, step.dt, rhs[k]);
      if (coordinate && inputs.actuator_stiffness)
        diagonal[k] += add_actuator_forces(inputs.actuator_stiffness[g], inputs.actuator_damping[g], q[art.q_start(i)],
                                           qd[k], step.dt, rhs[k]);
    }
  }
}

int DenseArticulations::factor_and_solve(int a, const StepContext& step, Scalar* rhs) {
  // ABA factors in O(n) every step; H is factored every update_mass_matrix_interval steps (a constant H
  // once, its factor kept while the implicit diagonal stays the same). With implicit Coriolis forces
  // qdd = (M + theta dt C)^-1 rhs (an LU every step), while the constraint rows see M (its Cholesky factor)
  const ArticulationView& art = art_[a];
  ArticulationScratch& s = scratch_[a];
  const int nv = art.dof_count();
  const Scalar theta = step.settings.coriolis_implicitness;
  const VecX& diagonal = s.u;
  const bool constant = constant_mass_[a];
  if (theta == 0 && nv >= step.settings.aba_min_dofs) {
    factor_[a] = Factor::Aba;
    const int link = aba_factor(art, diagonal.data(), s);
    if (link >= 0) return art.qd_start(link);
    aba_solve(art, s, rhs);
    return -1;
  }
  const bool same_diagonal = factored_diagonal_[a].size() == nv && diagonal == factored_diagonal_[a];
  if (theta == 0 && factor_[a] == Factor::Cholesky && (constant ? same_diagonal : !step.refactor)) {
    cholesky_solve(s.H, rhs);
    return -1;
  }
  if (constant && constant_H_[a].size() > 0) {
    s.H = constant_H_[a];
  } else {
    if (step.settings.use_tile_gemm)
      mass_matrix_gemm(art, s);
    else
      crba(art, s);
    if (constant) constant_H_[a] = s.H;
  }
  s.H.diagonal() += diagonal;
  factored_diagonal_[a] = diagonal;
  factor_[a] = Factor::Cholesky;
  int bad;
  if (theta > 0) {
    bias_velocity_jacobian(art, step.in->joint_qd.data() + art.qd_begin(), s, s.C);
    s.C = s.H + theta * step.dt * s.C;
    implicit_lu_[a].compute(s.C);
    s.qd_step = Eigen::Map<const VecX>(rhs, nv);
    Eigen::Map<VecX>(rhs, nv) = implicit_lu_[a].solve(s.qd_step);
    bad = cholesky_factor(s.H);
  } else if (step.settings.fuse_cholesky) {
    bad = cholesky_factor_solve(s.H, rhs);
  } else {
    bad = cholesky_factor(s.H);
    if (bad < 0) cholesky_solve(s.H, rhs);
  }
  if (bad >= 0) factor_[a] = Factor::None;
  return bad;
}

void DenseArticulations::dynamics(const UnitPass& pass, const StepContext& step, const UnitInputs& inputs) {
  const int a = units_[pass.unit];
  const ArticulationView& art = art_[a];
  if (art.dof_count() == 0) return;
  ArticulationScratch& s = scratch(a);
  const int qd0 = art.qd_begin(), nv = art.dof_count();
  forward_kinematics(art, step.in->joint_q.data() + art.q_begin(), s);
  forward_velocity(art, step.in->joint_qd.data() + qd0, s);
  for (int i = 0; i < art.link_count(); ++i)
    s.S_world.middleCols(art.qd_start(i), art.dof(i)) =
        motion_xform(s.X_world[i].inverse()) * s.S.middleCols(art.qd_start(i), art.dof(i));
  Scalar* rhs = rhs_.data() + qd0;
  s.qdd_zero.setZero(nv);
  joint_forces(a, step, inputs, rhs, s.u);
  const int bad = factor_and_solve(a, step, rhs);
  step.factor_failure[a] = bad < 0 ? -1 : qd0 + bad;
  for (int k = 0; k < nv; ++k) step.qd[qd0 + k] = step.in->joint_qd[qd0 + k] + step.dt * rhs[k];
  for (const int k : rotational_[a]) step.qd[qd0 + k] *= step.keep;
}

void DenseArticulations::integrate(const UnitPass& pass, const StepContext& step) {
  const int a = units_[pass.unit];
  const ArticulationView& art = art_[a];
  const int q0 = art.q_begin(), qd0 = art.qd_begin();
  integrate_joints(art, step.in->joint_q.data() + q0, step.qd + qd0, step.dt, step.q_next + q0);
  bool diverged;
  divergence_test<Scalar>(step.q_next + q0, art.coord_count(), step.qd + qd0, step.energy_weight + qd0, art.dof_count(),
                          step.settings.divergence_speed, step.settings.divergence_energy, &diverged);
  step.diverged[a] = diverged || step.flagged[a];
}

void DenseArticulations::store(const UnitPass& pass, const StepContext& step) {
  const int a = units_[pass.unit];
  if (!step.diverged[a] && step.factor_failure[a] < 0) write_state(a, step);
}

void DenseArticulations::write_state(int a, const StepContext& step) {
  const ArticulationView& art = art_[a];
  State& out = *step.out;
  std::copy_n(step.q_next + art.q_begin(), art.coord_count(), out.joint_q.begin() + art.q_begin());
  std::copy_n(step.qd + art.qd_begin(), art.dof_count(), out.joint_qd.begin() + art.qd_begin());
  ArticulationScratch& s = scratch(a);
  forward_kinematics(art, out.joint_q.data() + art.q_begin(), s);
  forward_velocity(art, out.joint_qd.data() + art.qd_begin(), s);
  // each body at its own centre of mass (the model's, not the merged link's)
  auto com = [&](int b) { return Vec3(Eigen::Map<const Vec3>(&model_.body_com[3 * b])); };
  for (int i = 0; i < art.link_count(); ++i)
    store_body(s, i, Transform::identity(), com(art.body(i)), art.body(i), out);
  for (const WeldedBody& w : welded_[a]) store_body(s, w.link, w.offset, com(w.body), w.body, out);
}

const Scalar* DenseArticulations::link_wrenches(int a, const Scalar* body_f) {
  if (welded_[a].empty()) return body_f;
  const ArticulationView& art = art_[a];
  const ArticulationScratch& s = scratch_[a];
  auto pushed = [&](int b) { return Eigen::Map<const Vec6>(body_f + 6 * b).any(); };
  bool any = false;
  for (int i = 0; i < art.link_count() && !any; ++i) any = pushed(art.body(i));
  for (size_t k = 0; k < welded_[a].size() && !any; ++k) any = pushed(welded_[a][k].body);
  if (!any) return body_f;
  // a body's wrench [f at its centre of mass; torque] moves to its link's merged centre of mass
  auto add = [&](int b, int link, const Transform& offset) {
    const Transform& X = s.X_world[link];
    const Vec3 r = X.apply(offset.apply(Eigen::Map<const Vec3>(&model_.body_com[3 * b]))) - X.apply(art.com(link));
    Scalar* out = link_f_.data() + 6 * art.body(link);
    add_wrench_about(body_f + 6 * b, body_f + 6 * b + 3, r.data(), out + 3, out);
  };
  for (int i = 0; i < art.link_count(); ++i) std::fill_n(link_f_.data() + 6 * art.body(i), 6, 0);
  for (int i = 0; i < art.link_count(); ++i) add(art.body(i), i, Transform::identity());
  for (const WeldedBody& w : welded_[a]) add(w.body, w.link, w.offset);
  return link_f_.data();
}

void DenseArticulations::solve_mass(int a, Scalar* x) {
  if (factor_[a] == Factor::Aba)
    aba_solve(art_[a], scratch_[a], x);
  else
    cholesky_solve(scratch_[a].H, x);
}

void DenseArticulations::point_jacobian(int a, int link, const Vec3* p, const Vec3& d, Scalar sign, Scalar* J) const {
  // J qd = d . (the velocity of the body-fixed point p, or the angular velocity), over the dofs that move the link
  const ArticulationView& art = art_[a];
  const MatX& S = scratch_[a].S_world;
  for (int i = link; i >= 0; i = art.parent(i))
    for (int k = art.qd_start(i); k < art.qd_start(i) + art.dof(i); ++k)
      J[k] += sign * motion_along(S.col(k).data(), p ? p->data() : nullptr, d.data());
}

std::size_t DenseArticulations::bytes() const {
  auto size = [](const auto& m) { return static_cast<std::size_t>(m.size()) * sizeof(Scalar); };
  std::size_t n = (rhs_.size() + link_f_.size()) * sizeof(Scalar);
  for (const ArticulationScratch& s : scratch_) {
    n += (s.X_up.size() + s.X_world.size()) * sizeof(Transform) +
         (s.Xup.size() + s.I.size() + s.IC.size() + s.D_inv.size()) * sizeof(Mat6) +
         (s.c.size() + s.v.size() + s.a.size() + s.f.size() + s.pA.size()) * sizeof(Vec6);
    n += size(s.S) + size(s.U) + size(s.H) + size(s.S_world) + size(s.u) + size(s.C);
  }
  for (const MatX& H : constant_H_) n += size(H);
  return n;
}

}  // namespace novaphy
