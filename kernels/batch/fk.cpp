#include "kernels/batch/fk.h"

#include "kernels/batch/lane_math.h"

namespace novaphy {

using namespace lane_math;

template <typename T>
void batch_kinematics(const BatchTopology<T>& topo, const V<T>* q, BatchWork<T>& w, V<T>* o) {
  using L = typename BatchTopology<T>::Link;
  for (size_t i = 0; i < topo.link.size(); ++i) {
    const L& k = topo.link[i];
    const V<T>* x = q + k.q_start;
    V<T> Qrel[4], trel[3];
    switch (k.type) {
      case JointType::Revolute: {
        V<T> s, c;
        lane_sincos<T>(T(0.5) * x[0], &s, &c);
        for (int m = 0; m < 4; ++m) Qrel[m] = c * k.P0[m] + s * k.P1[m];
        const V<T> sin_q = 2 * s * c, versine = 2 * s * s;
        for (int m = 0; m < 3; ++m) trel[m] = k.T0[m] + sin_q * k.T1[m] + versine * k.T2[m];
        break;
      }
      case JointType::Prismatic:
        for (int m = 0; m < 4; ++m) Qrel[m] = V<T>{} + k.P0[m];
        for (int m = 0; m < 3; ++m) trel[m] = k.T0[m] + x[0] * k.T1[m];
        break;
      case JointType::Ball:
      case JointType::Free: {
        const V<T>* xq = k.type == JointType::Ball ? x : x + 3;
        V<T> QJ[4] = {xq[0], xq[1], xq[2], xq[3]}, tmp[4], Rb[3], bb[3];
        quat_normalize<T>(QJ);
        quat_mul(k.Qp, QJ, tmp);
        quat_mul(tmp, k.Qci, Qrel);
        for (int m = 0; m < 3; ++m) bb[m] = V<T>{} + k.b[m];
        quat_rotate<T>(QJ, bb, Rb);
        if (k.type == JointType::Free)
          for (int m = 0; m < 3; ++m) Rb[m] += x[m];
        mat_vec(k.Rp, Rb, trel);
        for (int m = 0; m < 3; ++m) trel[m] += k.tp[m];
        break;
      }
      case JointType::Fixed:
        for (int m = 0; m < 4; ++m) Qrel[m] = V<T>{} + k.P0[m];
        for (int m = 0; m < 3; ++m) trel[m] = V<T>{} + k.T0[m];
        break;
      case JointType::Distance:  // (maximal-coordinate joints: SolverFeatherstone refuses them)
      case JointType::D6:
      case JointType::Cable: break;
    }
    V<T>* Qi = &w.Q[4 * i];
    V<T>* pi = &w.p[3 * i];
    if (k.parent < 0) {
      for (int m = 0; m < 4; ++m) Qi[m] = Qrel[m];
      for (int m = 0; m < 3; ++m) pi[m] = trel[m];
    } else {
      quat_mul(&w.Q[4 * k.parent], Qrel, Qi);
      V<T> d[3];
      mat_vec(&w.R[9 * k.parent], trel, d);
      for (int m = 0; m < 3; ++m) pi[m] = w.p[3 * k.parent + m] + d[m];
    }
    quat_to_matrix<T>(Qi, &w.R[9 * i]);
  }
  for (int m = 0; m < 3; ++m) o[m] = w.p[m];
}

// link i's motion subspace columns s [dof][6] (batch_subspace's, for one link with dofs)
template <typename T>
inline void link_subspace(const BatchTopology<T>& topo, const BatchWork<T>& w, const V<T>* o, size_t i, V<T>* s) {
  const auto& k = topo.link[i];
  const V<T>* R = &w.R[9 * i];
  V<T> r[3];  // child joint frame origin relative to o
  mat_vec(R, k.tc, r);
  for (int m = 0; m < 3; ++m) r[m] += w.p[3 * i + m] - o[m];
  auto angular = [&](V<T>* col, const V<T>* axis) {
    for (int m = 0; m < 3; ++m) col[m] = axis[m];
    cross(r, axis, col + 3);
  };
  switch (k.type) {
    case JointType::Revolute: {
      V<T> axis[3];
      mat_vec(R, k.ac, axis);
      angular(s, axis);
      break;
    }
    case JointType::Prismatic:
      for (int m = 0; m < 3; ++m) s[m] = V<T>{};
      mat_vec(R, k.ac, s + 3);
      break;
    case JointType::Ball:
      for (int c = 0; c < 3; ++c) {
        const T e[3] = {k.Rc[c], k.Rc[3 + c], k.Rc[6 + c]};
        V<T> axis[3];
        mat_vec(R, e, axis);
        angular(s + 6 * c, axis);
      }
      break;
    case JointType::Free: {
      // qd in the parent joint frame: its axes are R_parent R_p
      V<T> Rpj[9];
      for (int m = 0; m < 9; ++m) Rpj[m] = V<T>{} + k.Rp[m];
      if (k.parent >= 0) {
        const V<T>* Rpar = &w.R[9 * k.parent];
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c)
            Rpj[3 * a + c] = Rpar[3 * a] * k.Rp[c] + Rpar[3 * a + 1] * k.Rp[3 + c] + Rpar[3 * a + 2] * k.Rp[6 + c];
      }
      for (int c = 0; c < 3; ++c) {
        const V<T> axis[3] = {Rpj[c], Rpj[3 + c], Rpj[6 + c]};
        angular(s + 6 * c, axis);
        V<T>* lin = s + 6 * (3 + c);
        for (int m = 0; m < 3; ++m) lin[m] = V<T>{}, lin[3 + m] = axis[m];
      }
      break;
    }
    case JointType::Fixed:
    case JointType::Distance:
    case JointType::D6:
    case JointType::Cable: break;
  }
}

// link i's velocity from its parent's and its columns s [dof][6] (batch_velocity's, for one link)
template <typename T>
inline void link_velocity(const BatchTopology<T>& topo, size_t i, const V<T>* s, const V<T>* qd, BatchWork<T>& w) {
  const auto& k = topo.link[i];
  V<T>* v = &w.v[6 * i];
  for (int m = 0; m < 6; ++m) v[m] = k.parent < 0 ? V<T>{} : w.v[6 * k.parent + m];
  for (int d = 0; d < k.dof; ++d) {
    const V<T> x = qd[k.qd_start + d];
    for (int m = 0; m < 6; ++m) v[m] += s[6 * d + m] * x;
  }
  if (k.type == JointType::Free)
    for (int m = 0; m < 3; ++m) {
      const V<T>* lin = s + 6 * 3;
      w.vrel[3 * i + m] =
          lin[3 + m] * qd[k.qd_start + 3] + lin[9 + m] * qd[k.qd_start + 4] + lin[15 + m] * qd[k.qd_start + 5];
    }
}

template <typename T>
void batch_subspace(const BatchTopology<T>& topo, const BatchWork<T>& w, const V<T>* o, V<T>* S) {
  for (size_t i = 0; i < topo.link.size(); ++i)
    if (topo.link[i].dof > 0) link_subspace(topo, w, o, i, S + 6 * topo.link[i].qd_start);
}

template <typename T>
void batch_velocity(const BatchTopology<T>& topo, const V<T>* S, const V<T>* qd, BatchWork<T>& w) {
  for (size_t i = 0; i < topo.link.size(); ++i) link_velocity(topo, i, S + 6 * topo.link[i].qd_start, qd, w);
}

template <typename T>
void batch_subspace_velocity(const BatchTopology<T>& topo, const V<T>* o, const V<T>* qd, BatchWork<T>& w) {
  for (size_t i = 0; i < topo.link.size(); ++i) {
    V<T> s[6 * 6];  // (a Free joint's six columns at most)
    if (topo.link[i].dof > 0) link_subspace(topo, w, o, i, s);
    link_velocity(topo, i, s, qd, w);
  }
}

#define NOVAPHY_INSTANTIATE(T)                                                                            \
  template void batch_kinematics(const BatchTopology<T>&, const Lanes<T>*, BatchWork<T>&, Lanes<T>*);     \
  template void batch_subspace(const BatchTopology<T>&, const BatchWork<T>&, const Lanes<T>*, Lanes<T>*); \
  template void batch_velocity(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, BatchWork<T>&); \
  template void batch_subspace_velocity(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, BatchWork<T>&);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
