#include "kernels/aba.h"

#include <Eigen/Cholesky>

#include "kernels/rnea.h"

namespace novaphy {

using JointMat = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

int aba(const ArticulationView& art, const Scalar* tau, const Vec3& gravity, const Scalar* body_f,
        ArticulationScratch& s, Scalar* qdd) {
  const int n = art.link_count();
  auto& IA = s.IC;
  for (int i = 0; i < n; ++i) {
    IA[i] = s.I[i];
    s.pA[i] = crf(s.v[i]) * (s.I[i] * s.v[i]) - link_external_force(art, s, body_f, i);
  }

  // backward pass: articulated inertias and bias forces
  for (int i = n - 1; i >= 0; --i) {
    const int d = art.dof(i);
    const int r = art.qd_start(i);
    const auto S_i = s.S.middleCols(r, d);
    auto U_i = s.U.middleCols(r, d);
    auto u_i = s.u.segment(r, d);
    U_i = IA[i] * S_i;
    if (d > 0) {
      // D = S^T IA S plus the armature's rotor inertia on the diagonal
      JointMat D = S_i.transpose() * U_i;
      D.diagonal() += Eigen::Map<const VecX>(art.joint_armature + art.qd_begin() + r, d);
      const Eigen::LLT<JointMat> llt(D);
      if (llt.info() != Eigen::Success) return i;
      s.D_inv[i].topLeftCorner(d, d) = llt.solve(JointMat::Identity(d, d));
      u_i = Eigen::Map<const VecX>(tau + r, d) - S_i.transpose() * s.pA[i];
    }
    const int p = art.parent(i);
    if (p < 0) continue;
    const auto D_inv = s.D_inv[i].topLeftCorner(d, d);
    const Mat6 Ia = IA[i] - U_i * D_inv * U_i.transpose();
    const Vec6 pa = s.pA[i] + Ia * s.c[i] + U_i * (D_inv * u_i);
    IA[p] += s.Xup[i].transpose() * Ia * s.Xup[i];
    s.pA[p] += s.Xup[i].transpose() * pa;
  }

  // forward pass: accelerations
  Vec6 a_world;
  a_world << Vec3::Zero(), -gravity;
  for (int i = 0; i < n; ++i) {
    const int p = art.parent(i);
    const int d = art.dof(i);
    const int r = art.qd_start(i);
    const Vec6 a = s.Xup[i] * (p < 0 ? a_world : s.a[p]) + s.c[i];
    auto qdd_i = Eigen::Map<VecX>(qdd + r, d);
    if (d > 0) qdd_i = s.D_inv[i].topLeftCorner(d, d) * (s.u.segment(r, d) - s.U.middleCols(r, d).transpose() * a);
    s.a[i] = a + s.S.middleCols(r, d) * qdd_i;
  }
  return -1;
}

}  // namespace novaphy
