#include "kernels/batch/pgs.h"

#include <limits>

namespace novaphy {

namespace {

template <typename T>
using V = Lanes<T>;
template <typename T>
using M = IntLanes<T>;

template <typename T>
V<T> dot(const V<T>* a, const V<T>* b, int n) {
  V<T> s{};
  for (int k = 0; k < n; ++k) s += a[k] * b[k];
  return s;
}

// qd += z * impulse in the lanes of `on`; the others keep their bits
template <typename T>
void apply(const V<T>* z, const V<T>& impulse, const M<T>& on, int n, V<T>* qd) {
  for (int k = 0; k < n; ++k) qd[k] = on ? qd[k] + z[k] * impulse : qd[k];
}

template <typename T>
M<T> finite(const V<T>& x) {
  return lane_abs<T>(x) <= std::numeric_limits<T>::max();
}

// J qd over the dofs [begin, end) outside which the row is zero, in four sums (the dofs k = 0, 1,
// 2, 3 mod 4) so that the latency of one does not hold up the others; skipping the zero terms
// changes no bit
template <typename T>
V<T> row_velocity(const V<T>* j, const V<T>* qd, int begin, int end) {
  V<T> v0{}, v1{}, v2{}, v3{};
  int k = begin & ~3;
  for (; k + 4 <= end; k += 4) {
    v0 += j[k] * qd[k];
    v1 += j[k + 1] * qd[k + 1];
    v2 += j[k + 2] * qd[k + 2];
    v3 += j[k + 3] * qd[k + 3];
  }
  if (k < end) v0 += j[k] * qd[k];
  if (k + 1 < end) v1 += j[k + 1] * qd[k + 1];
  if (k + 2 < end) v2 += j[k + 2] * qd[k + 2];
  return (v0 + v1) + (v2 + v3);
}

}  // namespace

template <typename T>
int batch_pgs_solve(const BatchRows<T>& rows, const PgsSettings& settings, V<T>* qd) {
  const int n = rows.dofs;
  const T cfm = static_cast<T>(settings.cfm), s = static_cast<T>(settings.friction_smoothing);
  auto J = [&](int r) { return rows.J + static_cast<size_t>(r) * n; };
  auto z = [&](int r) { return rows.MinvJT + static_cast<size_t>(r) * n; };
  V<T>* lambda = rows.lambda;
  for (int r = 0; r < rows.count; ++r) {
    const V<T> W = dot<T>(J(r), z(r), n) + (cfm + rows.cfm[r]);
    rows.inv_mass[r] = (rows.active[r] != 0) & (W > T(1e-12)) ? 1 / W : V<T>{};
  }
  for (int r = 0; r < rows.count; ++r) apply<T>(z(r), lambda[r], rows.active[r], n, qd);
  // unconstrained step of one row: the impulse that would bring J qd to its target
  auto velocity = [&](int r) { return row_velocity<T>(J(r), qd, rows.nonzero_begin[r], rows.nonzero_end[r]); };
  auto step = [&](int r) {
    return -(velocity(r) - rows.target[r] + (cfm + rows.cfm[r]) * lambda[r]) * rows.inv_mass[r];
  };
  // a lane sweeps while some row's impulse in it moved by more than tolerance / (J M^-1 J^T) in the
  // sweep before (with tolerance 0: moved at all; a sweep that moves none is a fixed point, which
  // every further sweep would repeat bit for bit). A lane that stopped keeps its bits, as if alone in
  // its block; so does a lane whose impulse did not change (no z * 0 added to its velocities), and a
  // row that changed no lane's impulse is not applied
  const T tolerance = static_cast<T>(settings.tolerance);
  auto moved = [&](int r, const V<T>& change) { return lane_abs<T>(change) > tolerance * rows.inv_mass[r]; };
  M<T> live = ~M<T>{};
  int it = 0;
  for (; it < settings.iterations && any_lane<T>(live); ++it) {
    M<T> moving{};
    for (int r = 0; r < rows.count; ++r) {
      // a lane gone non-finite keeps its impulse, so NaN does not spread through the rows
      if (rows.kind[r] != RowKind::FrictionPair) {
        const V<T> sum = lambda[r] + step(r);
        V<T> next;
        if (rows.kind[r] == RowKind::Unilateral) {
          next = sum > 0 ? sum : V<T>{};
        } else {
          const V<T> b = rows.kind[r] == RowKind::FrictionOne ? rows.mu[r] * lambda[rows.normal[r]] : rows.bound[r];
          next = sum < -b ? -b : (sum > b ? b : sum);
        }
        const M<T> on = live & rows.active[r] & finite<T>(next) & (next != lambda[r]);
        if (!any_lane<T>(on)) continue;
        apply<T>(z(r), next - lambda[r], on, n, qd);
        moving |= on & moved(r, next - lambda[r]);
        lambda[r] = on ? next : lambda[r];
        continue;
      }
      // friction pair: both tangents, bounded by mu * normal impulse (box, disk or a blend)
      const int r2 = r + 1;
      const V<T> limit = rows.mu[r] * lambda[rows.normal[r]];
      const V<T> l1 = lambda[r] + step(r), l2 = lambda[r2] + step(r2);
      const V<T> box1 = l1 < -limit ? -limit : (l1 > limit ? limit : l1);
      const V<T> box2 = l2 < -limit ? -limit : (l2 > limit ? limit : l2);
      const V<T> norm = lane_sqrt<T>(l1 * l1 + l2 * l2);
      const V<T> scale = norm > limit ? limit / norm : V<T>{} + 1;
      const V<T> new1 = (1 - s) * box1 + s * scale * l1, new2 = (1 - s) * box2 + s * scale * l2;
      const M<T> on = live & rows.active[r] & finite<T>(new1) & finite<T>(new2);
      const M<T> on1 = on & (new1 != lambda[r]), on2 = on & (new2 != lambda[r2]);
      if (any_lane<T>(on1)) apply<T>(z(r), new1 - lambda[r], on1, n, qd);
      if (any_lane<T>(on2)) apply<T>(z(r2), new2 - lambda[r2], on2, n, qd);
      moving |= (on1 & moved(r, new1 - lambda[r])) | (on2 & moved(r2, new2 - lambda[r2]));
      lambda[r] = on1 ? new1 : lambda[r];
      lambda[r2] = on2 ? new2 : lambda[r2];
      ++r;  // the second tangent
    }
    live = moving;
  }
  return it;
}

template int batch_pgs_solve(const BatchRows<float>&, const PgsSettings&, Lanes<float>*);
template int batch_pgs_solve(const BatchRows<double>&, const PgsSettings&, Lanes<double>*);

}  // namespace novaphy
