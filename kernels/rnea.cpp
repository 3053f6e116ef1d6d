#include "kernels/rnea.h"

#include "kernels/fk.h"

namespace novaphy {

Vec6 link_external_force(const ArticulationView& art, const ArticulationScratch& s, const Scalar* body_f, int i) {
  if (body_f == nullptr) return Vec6::Zero();
  const Scalar* w = body_f + 6 * art.body(i);
  const Mat3 Rt = s.X_world[i].rotation().transpose();
  const Vec3 f = Rt * Vec3(w[0], w[1], w[2]);
  const Vec3 t = Rt * Vec3(w[3], w[4], w[5]);
  Vec6 f_ext;
  f_ext << t + art.com(i).cross(f), f;
  return f_ext;
}

void rnea(const ArticulationView& art, const Scalar* qdd, const Vec3& gravity, const Scalar* body_f,
          ArticulationScratch& s, Scalar* tau) {
  const int n = art.link_count();
  Vec6 a_world;
  a_world << Vec3::Zero(), -gravity;

  // forward pass: accelerations and link forces
  for (int i = 0; i < n; ++i) {
    const int p = art.parent(i);
    const int d = art.dof(i);
    const Vec6 a_p = p < 0 ? a_world : s.a[p];
    s.a[i] =
        s.Xup[i] * a_p + s.S.middleCols(art.qd_start(i), d) * Eigen::Map<const VecX>(qdd + art.qd_start(i), d) + s.c[i];
    s.f[i] = s.I[i] * s.a[i] + crf(s.v[i]) * (s.I[i] * s.v[i]) - link_external_force(art, s, body_f, i);
  }

  // backward pass: project onto the joints, accumulate into parents
  for (int i = n - 1; i >= 0; --i) {
    const int d = art.dof(i);
    const int r = art.qd_start(i);
    Eigen::Map<VecX>(tau + r, d) =
        s.S.middleCols(r, d).transpose() * s.f[i] + Eigen::Map<const VecX>(art.joint_armature + art.qd_begin() + r, d)
                                                        .cwiseProduct(Eigen::Map<const VecX>(qdd + r, d));
    const int p = art.parent(i);
    if (p >= 0) s.f[p] += s.Xup[i].transpose() * s.f[i];
  }
}

void bias_velocity_jacobian(const ArticulationView& art, const Scalar* qd, ArticulationScratch& s, MatX& C) {
  const int nv = art.dof_count();
  C.resize(nv, nv);
  s.qd_step = Eigen::Map<const VecX>(qd, nv);
  s.qdd_zero.setZero(nv);
  for (int k = 0; k < nv; ++k) {
    s.qd_step[k] = qd[k] + 1;
    forward_velocity(art, s.qd_step.data(), s);
    rnea(art, s.qdd_zero.data(), Vec3::Zero(), nullptr, s, C.col(k).data());
    s.qd_step[k] = qd[k] - 1;
    forward_velocity(art, s.qd_step.data(), s);
    rnea(art, s.qdd_zero.data(), Vec3::Zero(), nullptr, s, s.tau_step.data());
    C.col(k) = 0.5 * (C.col(k) - s.tau_step);
    s.qd_step[k] = qd[k];
  }
  forward_velocity(art, qd, s);
}

void passive_force(const ArticulationView& art, const Scalar* q, const Scalar* qd, Scalar* tau_passive) {
  const int qd0 = art.qd_begin();
  const int q0 = art.q_begin();
  for (int i = 0; i < art.link_count(); ++i) {
    const int dof = art.qd_start(i);
    for (int k = 0; k < art.dof(i); ++k) tau_passive[dof + k] = -art.joint_damping[qd0 + dof + k] * qd[dof + k];
    const JointType type = art.type(i);
    if (type == JointType::Revolute || type == JointType::Prismatic) {
      const int c = art.q_start(i);
      tau_passive[dof] -= art.joint_stiffness[qd0 + dof] * (q[c] - art.joint_q_ref[q0 + c]);
    }
  }
}

}  // namespace novaphy
