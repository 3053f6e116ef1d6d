// Small vector algebra on lanes (quaternions [x, y, z, w], 3-vectors, row-major 3x3 matrices, spatial
// inertias [m, h, J]): the pieces the batched kernels and the engine's block stages compose. Each works
// componentwise on Lanes<T> (or on a plain number where the template allows), the same operations in
// the same order wherever it is used.
#pragma once

#include "kernels/lanes.h"

namespace novaphy::lane_math {

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

// c = R(Q) x + p - o: the point x of a body at pose (p, Q), relative to o
template <typename T>
inline void body_point(const V<T>* p, const V<T>* Q, const V<T>* x, const V<T>* o, V<T>* c) {
  V<T> r[3];
  quat_rotate<T>(Q, x, r);
  for (int m = 0; m < 3; ++m) c[m] = r[m] + p[m] - o[m];
}

}  // namespace novaphy::lane_math
