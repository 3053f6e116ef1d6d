#include "kernels/batch.h"

#include <algorithm>

namespace novaphy {

namespace {

template <typename T>
using V = Lanes<T>;

// quaternions [x, y, z, w]
template <typename A, typename B, typename C>
inline void quat_mul(const A* a, const B* b, C* out) {
  const C x = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1];
  const C y = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0];
  const C z = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3];
  const C w = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2];
  out[0] = x, out[1] = y, out[2] = z, out[3] = w;
}

template <typename T>
inline void quat_normalize(V<T>* q) {
  const V<T> inv = 1 / lane_sqrt<T>(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int k = 0; k < 4; ++k) q[k] *= inv;
}

// rotation matrix (row-major) of a unit quaternion
template <typename T>
inline void quat_to_matrix(const V<T>* q, V<T>* R) {
  const V<T> x = q[0], y = q[1], z = q[2], w = q[3];
  const V<T> xx = x * x, yy = y * y, zz = z * z, xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
  R[0] = 1 - 2 * (yy + zz), R[1] = 2 * (xy - wz), R[2] = 2 * (xz + wy);
  R[3] = 2 * (xy + wz), R[4] = 1 - 2 * (xx + zz), R[5] = 2 * (yz - wx);
  R[6] = 2 * (xz - wy), R[7] = 2 * (yz + wx), R[8] = 1 - 2 * (xx + yy);
}

// v rotated by the unit quaternion q
template <typename T>
inline void quat_rotate(const V<T>* q, const V<T>* v, V<T>* out) {
  // t = 2 u x v; out = v + w t + u x t
  const V<T> tx = 2 * (q[1] * v[2] - q[2] * v[1]), ty = 2 * (q[2] * v[0] - q[0] * v[2]),
             tz = 2 * (q[0] * v[1] - q[1] * v[0]);
  out[0] = v[0] + q[3] * tx + q[1] * tz - q[2] * ty;
  out[1] = v[1] + q[3] * ty + q[2] * tx - q[0] * tz;
  out[2] = v[2] + q[3] * tz + q[0] * ty - q[1] * tx;
}

template <typename M, typename X, typename Y>
inline void mat_vec(const M* R, const X* x, Y* y) {  // y = R x, R row-major 3x3
  for (int r = 0; r < 3; ++r) y[r] = R[3 * r] * x[0] + R[3 * r + 1] * x[1] + R[3 * r + 2] * x[2];
}

template <typename A, typename B, typename C>
inline void cross(const A* a, const B* b, C* out) {
  const C x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
  out[0] = x, out[1] = y, out[2] = z;
}

// f = I m for an inertia [m, h, J] (10) and a motion vector m [w; v]: [J w + h x v; m v + w x h]
template <typename T>
inline void apply_inertia(const V<T>* I, const V<T>* m, V<T>* f) {
  const V<T>* h = I + 1;
  const V<T>* J = I + 4;  // xx yy zz xy xz yz
  const V<T>* w = m;
  const V<T>* v = m + 3;
  V<T> hv[3], wh[3];
  cross(h, v, hv);
  cross(w, h, wh);
  f[0] = J[0] * w[0] + J[3] * w[1] + J[4] * w[2] + hv[0];
  f[1] = J[3] * w[0] + J[1] * w[1] + J[5] * w[2] + hv[1];
  f[2] = J[4] * w[0] + J[5] * w[1] + J[2] * w[2] + hv[2];
  for (int k = 0; k < 3; ++k) f[3 + k] = I[0] * v[k] + wh[k];
}

template <typename T>
inline V<T> dot6(const V<T>* a, const V<T>* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5];
}

// the unit quaternion exp(r / 2) of a rotation vector r
template <typename T>
inline void quat_exp(const V<T>* r, V<T>* q) {
  const V<T> angle = lane_sqrt<T>(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  const IntLanes<T> small = angle < T(1e-12);
  const V<T> safe = small ? V<T>{} + 1 : angle;
  V<T> s, c;
  lane_sincos<T>(T(0.5) * safe, &s, &c);
  const V<T> k = small ? V<T>{} + T(0.5) : s / safe;
  for (int i = 0; i < 3; ++i) q[i] = k * r[i];
  q[3] = small ? V<T>{} + 1 : c;
}

template <typename D, typename S>
void copy_n(const S* from, int n, D* to) {
  for (int k = 0; k < n; ++k) to[k] = static_cast<D>(from[k]);
}

}  // namespace

template <typename T>
BatchTopology<T>::BatchTopology(const ArticulationView& art) {
  const int n = art.link_count();
  link.resize(n);
  coord_count = art.coord_count();
  dof_count = art.dof_count();
  dof_parent.assign(dof_count, -1);
  coord_of_dof.assign(dof_count, -1);
  std::vector<int> last_dof(n, -1);  // deepest dof at or above each link
  for (int i = 0; i < n; ++i) {
    Link& L = link[i];
    L.type = art.type(i);
    L.parent = art.parent(i);
    L.q_start = art.q_start(i);
    L.qd_start = art.qd_start(i);
    L.dof = art.dof(i);
    int up = L.parent < 0 ? -1 : last_dof[L.parent];
    for (int k = 0; k < L.dof; ++k) {
      dof_parent[L.qd_start + k] = up;
      up = L.qd_start + k;
    }
    last_dof[i] = up;
    if (L.type == JointType::Revolute || L.type == JointType::Prismatic) coord_of_dof[L.qd_start] = L.q_start;

    const Transform Xp = art.X_p(i), Xc = art.X_c(i), Xci = Xc.inverse();
    const Vec3 a = art.axis(i);
    const Mat3 Rp = Xp.rotation();
    const Vec3 b = Xci.p;
    auto quat = [](const Quat& q, T* out) { out[0] = q.x(), out[1] = q.y(), out[2] = q.z(), out[3] = q.w(); };
    const Quat P0 = Xp.q * Xci.q;
    const Quat P1 = Xp.q * Quat(0, a.x(), a.y(), a.z()) * Xci.q;
    quat(P0, L.P0);
    quat(P1, L.P1);
    quat(Xp.q, L.Qp);
    quat(Xci.q, L.Qci);
    const Mat3 Rc = Xc.rotation();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        L.Rp[3 * r + c] = static_cast<T>(Rp(r, c)), L.Rc[3 * r + c] = static_cast<T>(Rc(r, c));
    const Vec3 T0 = Xp.p + Rp * b;
    Vec3 T1 = Vec3::Zero(), T2 = Vec3::Zero();
    if (L.type == JointType::Revolute) T1 = Rp * a.cross(b), T2 = Rp * a.cross(a.cross(b));
    if (L.type == JointType::Prismatic) T1 = Rp * a;
    const Vec3 ac = Rc * a;
    copy_n(Xp.p.data(), 3, L.tp);
    copy_n(T0.data(), 3, L.T0);
    copy_n(T1.data(), 3, L.T1);
    copy_n(T2.data(), 3, L.T2);
    copy_n(b.data(), 3, L.b);
    copy_n(Xc.p.data(), 3, L.tc);
    copy_n(ac.data(), 3, L.ac);
  }
  ancestor_start.assign(1, 0);
  row_start.resize(dof_count);
  for (int k = 0; k < dof_count; ++k) {
    const size_t first = ancestors.size();
    for (int j = dof_parent[k]; j >= 0; j = dof_parent[j]) ancestors.push_back(j);
    std::reverse(ancestors.begin() + first, ancestors.end());
    ancestor_start.push_back(static_cast<int>(ancestors.size()));
    row_start[k] = packed_index(k, 0);
  }
  run_start.assign(1, 0);
  for (int k = 0; k < dof_count; ++k) {
    for (int p = ancestor_start[k]; p < ancestor_start[k + 1]; ++p) {
      const bool extends = static_cast<int>(ancestor_runs.size()) > run_start[k] &&
                           ancestor_runs.back().dof + ancestor_runs.back().count == ancestors[p];
      if (extends)
        ++ancestor_runs.back().count;
      else
        ancestor_runs.push_back({ancestors[p], 1});
    }
    run_start.push_back(static_cast<int>(ancestor_runs.size()));
  }
  link_dof_start.assign(1, 0);
  for (int i = 0; i < n; ++i) {
    const int d = last_dof[i];
    if (d >= 0) {
      link_dofs.insert(link_dofs.end(), ancestors.begin() + ancestor_start[d],
                       ancestors.begin() + ancestor_start[d + 1]);
      link_dofs.push_back(d);
    }
    link_dof_start.push_back(static_cast<int>(link_dofs.size()));
  }
}

template <typename T>
void batch_set_params(const BatchTopology<T>& topo, const ArticulationView& art, int lane, V<T>* data) {
  const int n = static_cast<int>(topo.link.size()), nv = topo.dof_count;
  V<T>* x = data;
  for (int i = 0; i < n; ++i) {
    const int b = art.body(i);
    x[i][lane] = static_cast<T>(art.body_mass[b]);
    for (int m = 0; m < 3; ++m) x[n + 3 * i + m][lane] = static_cast<T>(art.body_com[3 * b + m]);
    const int order[6] = {0, 4, 8, 1, 2, 5};  // xx yy zz xy xz yz of the row-major 3x3
    for (int m = 0; m < 6; ++m) x[4 * n + 6 * i + m][lane] = static_cast<T>(art.body_inertia[9 * b + order[m]]);
  }
  for (int k = 0; k < nv; ++k) {
    const int g = art.qd_begin() + k;
    x[10 * n + k][lane] = static_cast<T>(art.joint_armature[g]);
    x[10 * n + nv + k][lane] = static_cast<T>(art.joint_damping[g]);
    x[10 * n + 2 * nv + k][lane] = static_cast<T>(art.joint_stiffness[g]);
    const int c = topo.coord_of_dof[k];  // spring rest positions of the one-coordinate joints
    x[10 * n + 3 * nv + k][lane] = static_cast<T>(c < 0 ? 0 : art.joint_q_ref[art.q_begin() + c]);
  }
}

template <typename T>
void BatchWork<T>::resize(const BatchTopology<T>& topo) {
  const size_t n = topo.link.size();
  Q.resize(4 * n), p.resize(3 * n), R.resize(9 * n);
  v.resize(6 * n), a.resize(6 * n), f.resize(6 * n), I.resize(10 * n), vrel.resize(3 * n);
  q.resize(topo.coord_count), qd.resize(topo.dof_count), x.resize(topo.dof_count), tau.resize(topo.dof_count);
  diag.resize(topo.dof_count), f_ext.resize(6 * n), q_next.resize(topo.coord_count), drive.resize(4 * topo.dof_count);
  IJ.resize(6 * (topo.dof_count + 1));
}

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
    case JointType::Fixed: break;
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

template <typename T>
void batch_link_inertia(const BatchTopology<T>& topo, const BatchParams<T>& params, const V<T>* o, BatchWork<T>& w) {
  for (size_t i = 0; i < topo.link.size(); ++i) {
    const V<T>* R = &w.R[9 * i];
    const V<T> m = params.mass[i];
    const V<T>* Ib = params.inertia + 6 * i;
    V<T> c[3];  // centre of mass relative to o
    mat_vec(R, params.com + 3 * i, c);
    for (int k = 0; k < 3; ++k) c[k] += w.p[3 * i + k] - o[k];
    // R I_b R^T (I_b symmetric: xx yy zz xy xz yz)
    V<T> RI[9];
    for (int r = 0; r < 3; ++r) {
      RI[3 * r] = R[3 * r] * Ib[0] + R[3 * r + 1] * Ib[3] + R[3 * r + 2] * Ib[4];
      RI[3 * r + 1] = R[3 * r] * Ib[3] + R[3 * r + 1] * Ib[1] + R[3 * r + 2] * Ib[5];
      RI[3 * r + 2] = R[3 * r] * Ib[4] + R[3 * r + 1] * Ib[5] + R[3 * r + 2] * Ib[2];
    }
    auto rir = [&](int a, int b) {
      return RI[3 * a] * R[3 * b] + RI[3 * a + 1] * R[3 * b + 1] + RI[3 * a + 2] * R[3 * b + 2];
    };
    V<T>* I = &w.I[10 * i];
    I[0] = m;
    for (int k = 0; k < 3; ++k) I[1 + k] = m * c[k];
    // J = I_c + m (|c|^2 1 - c c^T)
    I[4] = rir(0, 0) + m * (c[1] * c[1] + c[2] * c[2]);
    I[5] = rir(1, 1) + m * (c[0] * c[0] + c[2] * c[2]);
    I[6] = rir(2, 2) + m * (c[0] * c[0] + c[1] * c[1]);
    I[7] = rir(0, 1) - m * c[0] * c[1];
    I[8] = rir(0, 2) - m * c[0] * c[2];
    I[9] = rir(1, 2) - m * c[1] * c[2];
  }
}

template <typename T>
void batch_bias(const BatchTopology<T>& topo, const V<T>* S, const V<T>* gravity, const V<T>* f_ext, BatchWork<T>& w,
                V<T>* tau) {
  using L = typename BatchTopology<T>::Link;
  const int n = static_cast<int>(topo.link.size());
  for (int i = 0; i < n; ++i) {
    const L& k = topo.link[i];
    const V<T>* v = &w.v[6 * i];
    V<T>* a = &w.a[6 * i];
    // the joint's own velocity v_J and c = dS/dt qd
    V<T> vJ[6], c[6];
    for (int m = 0; m < 6; ++m) vJ[m] = k.parent < 0 ? v[m] : v[m] - w.v[6 * k.parent + m];
    if (k.type == JointType::Free) {
      // S is fixed in the parent, but the point its linear part names moves with the child
      for (int m = 0; m < 6; ++m) c[m] = V<T>{};
      if (k.parent >= 0) {
        const V<T>* vp = &w.v[6 * k.parent];
        cross(vp, vJ, c);
        V<T> t1[3], t2[3];
        cross(vp + 3, vJ, t1);
        cross(vp, vJ + 3, t2);
        for (int m = 0; m < 3; ++m) c[3 + m] = t1[m] + t2[m];
      }
      V<T> t[3];
      cross(&w.vrel[3 * i], vJ, t);
      for (int m = 0; m < 3; ++m) c[3 + m] += t[m];
    } else {
      // S is fixed in the child: c = v x v_J
      cross(v, vJ, c);
      V<T> t1[3], t2[3];
      cross(v + 3, vJ, t1);
      cross(v, vJ + 3, t2);
      for (int m = 0; m < 3; ++m) c[3 + m] = t1[m] + t2[m];
    }
    for (int m = 0; m < 6; ++m)
      a[m] = (k.parent < 0 ? (m < 3 ? V<T>{} : -gravity[m - 3]) : w.a[6 * k.parent + m]) + c[m];
    // f = I a + v x* (I v) - f_ext
    V<T> Iv[6], Ia[6];
    const V<T>* I = &w.I[10 * i];
    apply_inertia<T>(I, v, Iv);
    apply_inertia<T>(I, a, Ia);
    V<T>* f = &w.f[6 * i];
    V<T> t1[3], t2[3], t3[3];
    cross(v, Iv, t1);
    cross(v + 3, Iv + 3, t2);
    cross(v, Iv + 3, t3);
    for (int m = 0; m < 3; ++m) f[m] = Ia[m] + t1[m] + t2[m], f[3 + m] = Ia[3 + m] + t3[m];
    if (f_ext)
      for (int m = 0; m < 6; ++m) f[m] -= f_ext[6 * i + m];
  }
  for (int i = n - 1; i >= 0; --i) {
    const L& k = topo.link[i];
    const V<T>* f = &w.f[6 * i];
    for (int d = 0; d < k.dof; ++d) tau[k.qd_start + d] = dot6<T>(S + 6 * (k.qd_start + d), f);
    if (k.parent >= 0)
      for (int m = 0; m < 6; ++m) w.f[6 * k.parent + m] += f[m];
  }
}

template <typename T>
void batch_mass_matrix(const BatchTopology<T>& topo, const BatchParams<T>& params, const V<T>* S, BatchWork<T>& w,
                       V<T>* H) {
  const int n = static_cast<int>(topo.link.size());
  for (int i = n - 1; i > 0; --i) {
    const int p = topo.link[i].parent;
    if (p >= 0)
      for (int m = 0; m < 10; ++m) w.I[10 * p + m] += w.I[10 * i + m];
  }
  for (int i = 0; i < n; ++i) {
    const auto& k = topo.link[i];
    for (int d = 0; d < k.dof; ++d) {
      const int r = k.qd_start + d;
      V<T> F[6];
      apply_inertia<T>(&w.I[10 * i], S + 6 * r, F);
      V<T>* row = H + topo.row_start[r];
      row[r] = dot6<T>(S + 6 * r, F) + params.armature[r];
      for (int p = topo.ancestor_start[r]; p < topo.ancestor_start[r + 1]; ++p) {
        const int j = topo.ancestors[p];
        row[j] = dot6<T>(S + 6 * j, F);
      }
    }
  }
}

template <typename T>
void batch_mass_matrix_gemm(const BatchTopology<T>& topo, const BatchParams<T>& params, const V<T>* S, BatchWork<T>& w,
                            V<T>* H) {
  constexpr int kT = kGemmTile;
  std::fill(H, H + topo.packed_size(), V<T>{});
  V<T>* IJ = w.IJ.data();
  V<T>* zero = IJ + 6 * topo.dof_count;  // the padding column
  std::fill(zero, zero + 6, V<T>{});
  for (size_t i = 0; i < topo.link.size(); ++i) {
    const int* D = topo.link_dofs.data() + topo.link_dof_start[i];
    const int d = topo.link_dof_start[i + 1] - topo.link_dof_start[i];
    if (d == 0) continue;
    // the link's Jacobian columns J_i (columns of S) and I_i J_i, both padded to whole tiles by the zero column
    for (int c = 0; c < d; ++c) apply_inertia<T>(&w.I[10 * i], S + 6 * D[c], IJ + 6 * c);
    for (int rt = 0; rt < d; rt += kT) {
      for (int ct = 0; ct <= rt; ct += kT) {
        // a tile of H in registers: rows rt.., columns ct.., each entry a sum over the 6 spatial components
        const V<T>* s[kT];
        const V<T>* f[kT];
        for (int a = 0; a < kT; ++a) {
          s[a] = rt + a < d ? S + 6 * D[rt + a] : zero;
          f[a] = ct + a < d ? IJ + 6 * (ct + a) : zero;
        }
        V<T> acc[kT][kT] = {};
#pragma GCC unroll 6
        for (int m = 0; m < 6; ++m) {
          V<T> sm[kT], fm[kT];
          for (int a = 0; a < kT; ++a) sm[a] = s[a][m], fm[a] = f[a][m];
          for (int a = 0; a < kT; ++a)
            for (int b = 0; b < kT; ++b) acc[a][b] += sm[a] * fm[b];
        }
        for (int a = 0; a < kT && rt + a < d; ++a) {
          V<T>* row = H + topo.row_start[D[rt + a]];
          for (int b = 0; b < kT && ct + b <= rt + a; ++b) row[D[ct + b]] += acc[a][b];
        }
      }
    }
  }
  for (int k = 0; k < topo.dof_count; ++k) H[topo.row_start[k] + k] += params.armature[k];
}

namespace {

// the most rows of a chain (dofs each the parent of the next) the factor and L x = y take together
constexpr int kChainGroup = 4;

// rows i of the runs, each i taking R rows' outer products in turn: L_i[j] -= L_c[i] L_c[j] for j among i's
// ancestors and i, c = each of the R rows in order (one load and store of L_i[j] for R products)
template <int R, typename T>
void take_outer_products(const BatchTopology<T>& topo, const V<T>* const* Lc, const typename BatchTopology<T>::Run* run,
                         int runs, V<T>* H) {
  for (int r = 0; r < runs; ++r)
    for (int i = run[r].dof; i < run[r].dof + run[r].count; ++i) {
      V<T> l_ci[R];
      for (int t = 0; t < R; ++t) l_ci[t] = Lc[t][i];
      V<T>* Li = H + topo.row_start[i];
      auto entry = [&](int j) {
        V<T> e = Li[j];
        for (int t = 0; t < R; ++t) e -= l_ci[t] * Lc[t][j];
        Li[j] = e;
      };
      for (int s = 0; s < r; ++s)
        for (int j = run[s].dof; j < run[s].dof + run[s].count; ++j) entry(j);
      for (int j = run[r].dof; j <= i; ++j) entry(j);
    }
}

}  // namespace

template <typename T>
IntLanes<T> batch_factor(const BatchTopology<T>& topo, V<T>* H, V<T>* x) {
  // row k of L is final once the rows below it have been folded in: divide it by the pivot, then take
  // its outer product off the rows of its ancestors (all of them ancestors of k too). Rows are taken in
  // groups of up to kChainGroup dofs in a chain (k, k - 1, ..., each the parent dof of the one before:
  // a multi-dof joint, a chain of hinges): each row of the group is finished and folded into the group's
  // rows above it in turn, then all the group's outer products come off the rows of the ancestors in one
  // pass. Each entry takes the same operations in the same order of k as one row at a time would, so the
  // result is the same to the bit; the pass loads and stores an entry once for the group's products
  using Run = typename BatchTopology<T>::Run;
  IntLanes<T> bad = IntLanes<T>{} - 1;
  auto runs_of = [&](int k, const Run** run) {
    *run = topo.ancestor_runs.data() + topo.run_start[k];
    return topo.run_start[k + 1] - topo.run_start[k];
  };
  for (int k = topo.dof_count - 1; k >= 0;) {
    int size = 1;
    while (size < kChainGroup && k - size >= 0 && topo.dof_parent[k - size + 1] == k - size) ++size;
    const V<T>* group[kChainGroup];
    for (int t = 0; t < size; ++t) {
      const int c = k - t;
      V<T>* Lc = H + topo.row_start[c];
      group[t] = Lc;
      const Run* run;
      const int runs = runs_of(c, &run);
      const V<T> d = Lc[c];
      bad = (d > 0) ? bad : IntLanes<T>{} + c;
      const V<T> inv = 1 / lane_sqrt<T>(d);
      Lc[c] = inv;  // the diagonal is kept inverted: solves multiply
      for (int r = 0; r < runs; ++r)
        for (int j = run[r].dof; j < run[r].dof + run[r].count; ++j) Lc[j] *= inv;
      for (int m = c - 1; m > k - size; --m) {  // the group's rows above c: their pivots come next
        V<T>* Lm = H + topo.row_start[m];
        const V<T> l_cm = Lc[m];
        const Run* above;
        const int above_runs = runs_of(m, &above);
        for (int r = 0; r < above_runs; ++r)
          for (int j = above[r].dof; j < above[r].dof + above[r].count; ++j) Lm[j] -= l_cm * Lc[j];
        Lm[m] -= l_cm * Lc[m];
      }
      if (x) {  // L^T y = x: row c of L is final
        const V<T> y = x[c] * inv;
        x[c] = y;
        for (int r = 0; r < runs; ++r)
          for (int j = run[r].dof; j < run[r].dof + run[r].count; ++j) x[j] -= Lc[j] * y;
      }
    }
    const Run* run;
    const int runs = runs_of(k - size + 1, &run);  // the ancestors of the group's top row
    switch (size) {
      case 1: take_outer_products<1>(topo, group, run, runs, H); break;
      case 2: take_outer_products<2>(topo, group, run, runs, H); break;
      case 3: take_outer_products<3>(topo, group, run, runs, H); break;
      default: take_outer_products<kChainGroup>(topo, group, run, runs, H); break;
    }
    k -= size;
  }
  return bad;
}

namespace {

// L x = y for the R rows k, k + 1, ... of a chain (each the parent dof of the next): their sums over the
// first row's ancestors side by side (independent chains of operations, each in its own order), then
// over the group's rows before each
template <int R, typename T>
void solve_lower_group(const BatchTopology<T>& topo, const V<T>* L, int k, V<T>* x) {
  const V<T>* Lt[R];
  V<T> y[R];
  for (int t = 0; t < R; ++t) Lt[t] = L + topo.row_start[k + t], y[t] = x[k + t];
  for (int r = topo.run_start[k]; r < topo.run_start[k + 1]; ++r) {
    const auto& run = topo.ancestor_runs[r];
    for (int j = run.dof; j < run.dof + run.count; ++j) {
      const V<T> x_j = x[j];
      for (int t = 0; t < R; ++t) y[t] -= Lt[t][j] * x_j;
    }
  }
  for (int t = 0; t < R; ++t) {
    for (int s = 0; s < t; ++s) y[t] -= Lt[t][k + s] * x[k + s];
    x[k + t] = y[t] * Lt[t][k + t];
  }
}

}  // namespace

template <typename T>
void batch_solve_lower(const BatchTopology<T>& topo, const V<T>* L, V<T>* x) {
  // row k: x_k = (x_k - the sum over its ancestors j, ascending, of L_kj x_j) / L_kk. A chain's rows (a
  // multi-dof joint, a chain of hinges) go up to four at a time: each row's sum takes the same operations
  // in the same order as alone, so the result is the same to the bit, and the group's sums overlap
  for (int k = 0; k < topo.dof_count;) {
    int size = 1;
    while (size < kChainGroup && k + size < topo.dof_count && topo.dof_parent[k + size] == k + size - 1) ++size;
    switch (size) {
      case 1: solve_lower_group<1>(topo, L, k, x); break;
      case 2: solve_lower_group<2>(topo, L, k, x); break;
      case 3: solve_lower_group<3>(topo, L, k, x); break;
      default: solve_lower_group<kChainGroup>(topo, L, k, x); break;
    }
    k += size;
  }
}

template <typename T>
void batch_solve(const BatchTopology<T>& topo, const V<T>* L, V<T>* x) {
  for (int k = topo.dof_count - 1; k >= 0; --k) {
    const V<T>* Lk = L + topo.row_start[k];
    const V<T> y = x[k] * Lk[k];
    x[k] = y;
    for (int r = topo.run_start[k]; r < topo.run_start[k + 1]; ++r) {
      const auto& run = topo.ancestor_runs[r];
      for (int j = run.dof; j < run.dof + run.count; ++j) x[j] -= Lk[j] * y;
    }
  }
  batch_solve_lower(topo, L, x);
}

template <typename T>
void batch_solve_unit(const BatchTopology<T>& topo, const V<T>* L, int unit, V<T>* x) {
  // L^T y = e_unit is nonzero only on unit and its ancestors
  for (int k = 0; k < topo.dof_count; ++k) x[k] = V<T>{};
  x[unit] = L[topo.row_start[unit] + unit];
  const int* a = topo.ancestors.data() + topo.ancestor_start[unit];
  const int m = topo.ancestor_start[unit + 1] - topo.ancestor_start[unit];
  for (int p = 0; p < m; ++p) x[a[p]] = -L[topo.row_start[unit] + a[p]] * x[unit];
  for (int p = m - 1; p >= 0; --p) {
    const int k = a[p];
    const V<T>* Lk = L + topo.row_start[k];
    const V<T> y = x[k] * Lk[k];
    x[k] = y;
    for (int r = 0; r < p; ++r) x[a[r]] -= Lk[a[r]] * y;
  }
  batch_solve_lower(topo, L, x);
}

template <typename T>
void batch_solve_many(const BatchTopology<T>& topo, const V<T>* L, int end, V<T>* x, int count, int stride) {
  // each entry of L loaded once for all right-hand sides, whose chains are independent
  auto rhs = [&](int r) { return x + static_cast<size_t>(r) * stride; };
  // L^T y = x: a dof past `end` has no descendant before it, so its entry stays zero
  for (int k = end - 1; k >= 0; --k) {
    const V<T>* Lk = L + topo.row_start[k];
    const V<T> d = Lk[k];
    for (int r = 0; r < count; ++r) rhs(r)[k] *= d;
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p) {
      const int i = topo.ancestors[p];
      const V<T> l = Lk[i];
      for (int r = 0; r < count; ++r) {
        V<T>* y = rhs(r);
        y[i] -= l * y[k];
      }
    }
  }
  for (int k = 0; k < topo.dof_count; ++k) {
    const V<T>* Lk = L + topo.row_start[k];
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p) {
      const int i = topo.ancestors[p];
      const V<T> l = Lk[i];
      for (int r = 0; r < count; ++r) {
        V<T>* y = rhs(r);
        y[k] -= l * y[i];
      }
    }
    const V<T> d = Lk[k];
    for (int r = 0; r < count; ++r) rhs(r)[k] *= d;
  }
}

template <typename T>
void batch_lane_factor(const BatchTopology<T>& topo, const V<T>* L, int lane, double* out) {
  for (int k = 0; k < topo.packed_size(); ++k) out[k] = L[k][lane];
}

template <typename T>
void batch_solve_packed(const BatchTopology<T>& topo, const double* L, double* x) {
  // L^T y = x: a zero entry stays zero and changes nothing (a contact row's J^T is zero off the path
  // of its link, so another leg's dofs are skipped)
  for (int k = topo.dof_count - 1; k >= 0; --k) {
    if (x[k] == 0) continue;
    const double* Lk = L + topo.row_start[k];
    const double y = x[k] * Lk[k];
    x[k] = y;
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p)
      x[topo.ancestors[p]] -= Lk[topo.ancestors[p]] * y;
  }
  for (int k = 0; k < topo.dof_count; ++k) {
    const double* Lk = L + topo.row_start[k];
    double y = x[k];
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p)
      y -= Lk[topo.ancestors[p]] * x[topo.ancestors[p]];
    x[k] = y * Lk[k];
  }
}

template <typename T>
void batch_integrate(const BatchTopology<T>& topo, const V<T>* q, const V<T>* qd, T dt, V<T>* q_out) {
  for (const auto& k : topo.link) {
    const V<T>* x = q + k.q_start;
    const V<T>* v = qd + k.qd_start;
    V<T>* y = q_out + k.q_start;
    switch (k.type) {
      case JointType::Revolute:
      case JointType::Prismatic: y[0] = x[0] + dt * v[0]; break;
      case JointType::Ball: {
        // the child frame turns by dt w (w in the child frame): q exp(dt w)
        const V<T> r[3] = {dt * v[0], dt * v[1], dt * v[2]};
        V<T> Q[4] = {x[0], x[1], x[2], x[3]}, E[4];
        quat_normalize<T>(Q);
        quat_exp<T>(r, E);
        quat_mul(Q, E, y);
        quat_normalize<T>(y);
        break;
      }
      case JointType::Free: {
        // w in the parent frame: exp(dt w) q
        for (int m = 0; m < 3; ++m) y[m] = x[m] + dt * v[3 + m];
        const V<T> r[3] = {dt * v[0], dt * v[1], dt * v[2]};
        V<T> Q[4] = {x[3], x[4], x[5], x[6]}, E[4];
        quat_normalize<T>(Q);
        quat_exp<T>(r, E);
        quat_mul(E, Q, y + 3);
        quat_normalize<T>(y + 3);
        break;
      }
      case JointType::Fixed: break;
    }
  }
}

#define NOVAPHY_BATCH_INSTANTIATE(T)                                                                                   \
  template struct BatchTopology<T>;                                                                                    \
  template struct BatchWork<T>;                                                                                        \
  template void batch_set_params(const BatchTopology<T>&, const ArticulationView&, int, Lanes<T>*);                    \
  template void batch_kinematics(const BatchTopology<T>&, const Lanes<T>*, BatchWork<T>&, Lanes<T>*);                  \
  template void batch_subspace(const BatchTopology<T>&, const BatchWork<T>&, const Lanes<T>*, Lanes<T>*);              \
  template void batch_velocity(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, BatchWork<T>&);              \
  template void batch_subspace_velocity(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, BatchWork<T>&);     \
  template void batch_link_inertia(const BatchTopology<T>&, const BatchParams<T>&, const Lanes<T>*, BatchWork<T>&);    \
  template void batch_bias(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, const Lanes<T>*, BatchWork<T>&,  \
                           Lanes<T>*);                                                                                 \
  template void batch_mass_matrix(const BatchTopology<T>&, const BatchParams<T>&, const Lanes<T>*, BatchWork<T>&,      \
                                  Lanes<T>*);                                                                          \
  template void batch_mass_matrix_gemm(const BatchTopology<T>&, const BatchParams<T>&, const Lanes<T>*, BatchWork<T>&, \
                                       Lanes<T>*);                                                                     \
  template IntLanes<T> batch_factor(const BatchTopology<T>&, Lanes<T>*, Lanes<T>*);                                    \
  template void batch_solve(const BatchTopology<T>&, const Lanes<T>*, Lanes<T>*);                                      \
  template void batch_solve_lower(const BatchTopology<T>&, const Lanes<T>*, Lanes<T>*);                                \
  template void batch_solve_unit(const BatchTopology<T>&, const Lanes<T>*, int, Lanes<T>*);                            \
  template void batch_solve_many(const BatchTopology<T>&, const Lanes<T>*, int, Lanes<T>*, int, int);                  \
  template void batch_lane_factor(const BatchTopology<T>&, const Lanes<T>*, int, double*);                             \
  template void batch_solve_packed(const BatchTopology<T>&, const double*, double*);                                   \
  template void batch_integrate(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, T, Lanes<T>*);

NOVAPHY_BATCH_INSTANTIATE(float)
NOVAPHY_BATCH_INSTANTIATE(double)

}  // namespace novaphy
