#include "kernels/osim.h"

#include "kernels/aba.h"
#include "kernels/cholesky.h"
#include "kernels/crba.h"

namespace novaphy {

int osim_inverse(const ArticulationView& art, ArticulationScratch& s, std::vector<Mat6>& Omega) {
  const int bad = aba_factor(art, nullptr, s);
  if (bad >= 0) return bad;
  const int n = art.link_count();
  Omega.resize(n);
  for (int i = 0; i < n; ++i) {
    const int d = art.dof(i), r = art.qd_start(i), p = art.parent(i);
    const auto S_i = s.S.middleCols(r, d);
    const auto U_i = s.U.middleCols(r, d);
    const auto D_inv = s.D_inv[i].topLeftCorner(d, d);
    // the joint's own share: its dofs' response to a wrench on the link
    Omega[i] = S_i * D_inv * S_i.transpose();
    if (p < 0) continue;
    // the parent's acceleration under the wrench the link passes on, seen from the link
    const Mat6 Q = s.Xup[i].transpose() * (Mat6::Identity() - U_i * D_inv * S_i.transpose());
    Omega[i] += Q.transpose() * Omega[p] * Q;
  }
  return -1;
}

int osim_inverse_ref(const ArticulationView& art, ArticulationScratch& s, std::vector<Mat6>& Omega) {
  mass_matrix_gemm(art, s);
  const int bad = cholesky_factor(s.H);
  if (bad >= 0) return bad;
  const int n = art.link_count();
  Omega.resize(n);
  for (int i = 0; i < n; ++i) {
    // H^-1 J_i^T column by column, then J_i times it
    MatX X = s.link_jacobian[i].transpose();
    for (int k = 0; k < 6; ++k) cholesky_solve(s.H, X.col(k).data());
    Omega[i] = s.link_jacobian[i] * X;
  }
  return -1;
}

}  // namespace novaphy
