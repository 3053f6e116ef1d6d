#include "kernels/aba.h"

#include <Eigen/Cholesky>

#include "kernels/rnea.h"

namespace novaphy {

namespace {

using JointMat = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

// the backward and forward passes over a factor: s.pA holds each link's own bias force on entry,
// c (the velocity-product accelerations, or none) and a_root the acceleration of the world;
// x holds tau on entry and qdd on return
void passes(const ArticulationView& art, ArticulationScratch& s, const Vec6* c, const Vec6& a_root, Scalar* x) {
  const int n = art.link_count();
  for (int i = n - 1; i >= 0; --i) {
    const int d = art.dof(i), r = art.qd_start(i);
    auto u_i = Eigen::Map<VecX>(x + r, d);
    if (d > 0) u_i -= s.S.middleCols(r, d).transpose() * s.pA[i];
    const int p = art.parent(i);
    if (p < 0) continue;
    const auto U_i = s.U.middleCols(r, d);
    const auto D_inv = s.D_inv[i].topLeftCorner(d, d);
    Vec6 pa = s.pA[i] + U_i * (D_inv * u_i);
    if (c) pa += s.IC[i] * c[i] - U_i * (D_inv * (U_i.transpose() * c[i]));  // Ia c
    s.pA[p] += s.Xup[i].transpose() * pa;
  }
  for (int i = 0; i < n; ++i) {
    const int p = art.parent(i), d = art.dof(i), r = art.qd_start(i);
    Vec6 a = s.Xup[i] * (p < 0 ? a_root : s.a[p]);
    if (c) a += c[i];
    auto x_i = Eigen::Map<VecX>(x + r, d);
    if (d > 0) x_i = s.D_inv[i].topLeftCorner(d, d) * (x_i - s.U.middleCols(r, d).transpose() * a);
    s.a[i] = a + s.S.middleCols(r, d) * x_i;
  }
}

}  // namespace

int aba_factor(const ArticulationView& art, const Scalar* diagonal, ArticulationScratch& s) {
  const int n = art.link_count();
  auto& IA = s.IC;
  for (int i = 0; i < n; ++i) IA[i] = s.I[i];
  for (int i = n - 1; i >= 0; --i) {
    const int d = art.dof(i), r = art.qd_start(i);
    auto U_i = s.U.middleCols(r, d);
    U_i = IA[i] * s.S.middleCols(r, d);
    if (d > 0) {
      // D = S^T IA S plus the armature's rotor inertia (and the caller's diagonal)
      JointMat D = s.S.middleCols(r, d).transpose() * U_i;
      D.diagonal() += Eigen::Map<const VecX>(art.joint_armature + art.qd_begin() + r, d);
      if (diagonal) D.diagonal() += Eigen::Map<const VecX>(diagonal + r, d);
      const Eigen::LLT<JointMat> llt(D);
      if (llt.info() != Eigen::Success) return i;
      s.D_inv[i].topLeftCorner(d, d) = llt.solve(JointMat::Identity(d, d));
    }
    const int p = art.parent(i);
    if (p < 0) continue;
    const Mat6 Ia = IA[i] - U_i * s.D_inv[i].topLeftCorner(d, d) * U_i.transpose();
    IA[p] += s.Xup[i].transpose() * Ia * s.Xup[i];
  }
  return -1;
}

void aba_solve(const ArticulationView& art, ArticulationScratch& s, Scalar* x) {
  for (int i = 0; i < art.link_count(); ++i) s.pA[i].setZero();
  passes(art, s, nullptr, Vec6::Zero(), x);
}

int aba(const ArticulationView& art, const Scalar* tau, const Vec3& gravity, const Scalar* body_f,
        ArticulationScratch& s, Scalar* qdd) {
  const int bad = aba_factor(art, nullptr, s);
  if (bad >= 0) return bad;
  for (int i = 0; i < art.link_count(); ++i)
    s.pA[i] = crf(s.v[i]) * (s.I[i] * s.v[i]) - link_external_force(art, s, body_f, i);
  std::copy(tau, tau + art.dof_count(), qdd);
  Vec6 a_root;
  a_root << Vec3::Zero(), -gravity;
  passes(art, s, s.c.data(), a_root, qdd);
  return -1;
}

}  // namespace novaphy
