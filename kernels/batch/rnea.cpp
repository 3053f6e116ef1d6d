#include "kernels/batch/rnea.h"

#include "kernels/batch/lane_math.h"

namespace novaphy {

using namespace lane_math;

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

#define NOVAPHY_INSTANTIATE(T)                                                                                        \
  template void batch_link_inertia(const BatchTopology<T>&, const BatchParams<T>&, const Lanes<T>*, BatchWork<T>&);   \
  template void batch_bias(const BatchTopology<T>&, const Lanes<T>*, const Lanes<T>*, const Lanes<T>*, BatchWork<T>&, \
                           Lanes<T>*);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
