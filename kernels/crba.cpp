#include "kernels/crba.h"

namespace novaphy {

void crba(const ArticulationView& art, ArticulationScratch& s) {
  const int n = art.link_count();
  for (int i = 0; i < n; ++i) s.IC[i] = s.I[i];
  for (int i = n - 1; i >= 0; --i) {
    const int p = art.parent(i);
    if (p >= 0) s.IC[p] += s.Xup[i].transpose() * s.IC[i] * s.Xup[i];
  }

  s.H.setZero(art.dof_count(), art.dof_count());
  for (int i = 0; i < n; ++i) {
    const int d_i = art.dof(i);
    if (d_i == 0) continue;
    const int r_i = art.qd_start(i);
    Eigen::Matrix<Scalar, 6, Eigen::Dynamic, 0, 6, 6> F = s.IC[i] * s.S.middleCols(r_i, d_i);
    const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6> H_ii =
        s.S.middleCols(r_i, d_i).transpose() * F;
    s.H.block(r_i, r_i, d_i, d_i) = 0.5 * (H_ii + H_ii.transpose());  // exactly symmetric
    // walk up the tree: H_ji = S_j^T X^T ... F
    for (int j = i; art.parent(j) >= 0;) {
      F = s.Xup[j].transpose() * F;
      j = art.parent(j);
      const int d_j = art.dof(j);
      if (d_j == 0) continue;
      const int r_j = art.qd_start(j);
      s.H.block(r_j, r_i, d_j, d_i) = s.S.middleCols(r_j, d_j).transpose() * F;
      s.H.block(r_i, r_j, d_i, d_j) = s.H.block(r_j, r_i, d_j, d_i).transpose();
    }
  }

  const int qd0 = art.qd_begin();
  for (int k = 0; k < art.dof_count(); ++k) s.H(k, k) += art.joint_armature[qd0 + k];
}

void mass_matrix_gemm(const ArticulationView& art, ArticulationScratch& s) {
  const int n = art.link_count();
  s.H.setZero(art.dof_count(), art.dof_count());
  s.link_jacobian.resize(n);
  for (auto& J : s.link_jacobian) J.resize(6, art.dof_count());
  for (int i = 0; i < n; ++i) {
    // J_i = Xup_i J_parent + S_i in its own columns (link coordinates)
    auto& J = s.link_jacobian[i];
    const int p = art.parent(i);
    if (p < 0)
      J.setZero();
    else
      J = s.Xup[i] * s.link_jacobian[p];
    J.middleCols(art.qd_start(i), art.dof(i)) = s.S.middleCols(art.qd_start(i), art.dof(i));
    const Eigen::Matrix<Scalar, 6, Eigen::Dynamic> IJ = s.I[i] * J;
    s.H.noalias() += J.transpose() * IJ;
  }
  const int qd0 = art.qd_begin();
  for (int k = 0; k < art.dof_count(); ++k) s.H(k, k) += art.joint_armature[qd0 + k];
}

}  // namespace novaphy
