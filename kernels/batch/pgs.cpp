#include "kernels/batch/pgs.h"

#include <algorithm>
#include <limits>
#include <vector>

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

// J qd of R rows at once (qd loaded once for all), over the dofs [begin, end) outside which the rows are zero,
// less the quads [skip_begin, skip_end) inside where they are zero too, in four sums a row (the dofs k = 0, 1,
// 2, 3 mod 4) so that the latency of one does not hold up the others; skipping the zero terms changes no bit
template <int R, typename T>
void row_velocities(const V<T>* const* j, const V<T>* qd, int begin, int end, int skip_begin, int skip_end, V<T>* v) {
  V<T> s[R][4] = {};
  auto quads = [&](int k, int until) {
    for (; k + 4 <= until; k += 4)
      for (int r = 0; r < R; ++r)
        for (int m = 0; m < 4; ++m) s[r][m] += j[r][k + m] * qd[k + m];
    return k;
  };
  int k = begin & ~3;
  if (skip_begin < skip_end) k = std::max(quads(k, skip_begin), skip_end);
  k = quads(k, end);
  for (int m = 0; m < 3; ++m)
    if (k + m < end)
      for (int r = 0; r < R; ++r) s[r][m] += j[r][k + m] * qd[k + m];
  for (int r = 0; r < R; ++r) v[r] = (s[r][0] + s[r][1]) + (s[r][2] + s[r][3]);
}

// apply for both rows of a pair in one pass over qd: the first row's impulse added before the second's, as
// two applies would add them
template <typename T>
void apply_pair(const V<T>* z1, const V<T>& i1, const M<T>& on1, const V<T>* z2, const V<T>& i2, const M<T>& on2, int n,
                V<T>* qd) {
  for (int k = 0; k < n; ++k) {
    const V<T> x = on1 ? qd[k] + z1[k] * i1 : qd[k];
    qd[k] = on2 ? x + z2[k] * i2 : x;
  }
}

}  // namespace

template <typename T>
int batch_pgs_solve(const BatchRows<T>& rows, const PgsSettings& settings, V<T>* qd, M<T>* converged) {
  const int n = rows.dofs;
  const T cfm = static_cast<T>(settings.cfm), s = static_cast<T>(settings.friction_smoothing);
  auto J = [&](int r) { return rows.J + static_cast<size_t>(r) * n; };
  auto z = [&](int r) { return rows.MinvJT + static_cast<size_t>(r) * n; };
  V<T>* lambda = rows.lambda;
  for (int r = 0; r < rows.count; ++r) {
    rows.inv_mass[r] = rows.active[r] != 0 ? row_inv_mass(dot<T>(J(r), z(r), n), cfm + rows.cfm[r]) : V<T>{};
  }
  for (int r = 0; r < rows.count; ++r) apply<T>(z(r), lambda[r], rows.active[r], n, qd);
  // unconstrained step of one row: the impulse that would bring J qd to its target
  auto velocity = [&](int r) {
    const V<T>* j = J(r);
    V<T> v;
    row_velocities<1, T>(&j, qd, rows.nonzero_begin[r], rows.nonzero_end[r], rows.zero_begin[r], rows.zero_end[r], &v);
    return v;
  };
  auto step_at = [&](int r, const V<T>& v) {
    return -(v - rows.target[r] + (cfm + rows.cfm[r]) * lambda[r]) * rows.inv_mass[r];
  };
  auto step = [&](int r) { return step_at(r, velocity(r)); };
  // a lane sweeps while some row's impulse in it moved by more than tolerance / (J M^-1 J^T) in the
  // sweep before (with tolerance 0: moved at all; a sweep that moves none is a fixed point, which
  // every further sweep would repeat bit for bit). A lane that stopped keeps its bits, as if alone in
  // its block; so does a lane whose impulse did not change (no z * 0 added to its velocities), and a
  // row that changed no lane's impulse is not applied
  const T tolerance = static_cast<T>(settings.tolerance);
  auto moved = [&](int r, const V<T>& change) { return lane_abs<T>(change) > tolerance * rows.inv_mass[r]; };
  // the friction cone rows of the contact whose normal is row r (0: none)
  auto cone_after_row = [&](int r) {
    return cone_after(
        r, rows.count, r, [&](int i) { return rows.kind[i]; }, [&](int i) { return rows.normal[i]; });
  };
  // each such contact's block of J_i M^-1 J_j^T over its rows (its cfm on the diagonal; 1 where a lane has no
  // row), once for all sweeps
  thread_local std::vector<ConeBlock<V<T>>> blocks;
  blocks.clear();
  for (int r = 0; r < rows.count; ++r) {
    const int g = cone_after_row(r);
    if (g == 0) continue;
    const int begin = rows.nonzero_begin[r], end = rows.nonzero_end[r];
    V<T>* A = blocks.emplace_back().A;
    for (int i = 0; i <= g; ++i) {
      A[i * kMaxContact + i] = rows.inv_mass[r + i] > 0 ? 1 / rows.inv_mass[r + i] : splat<V<T>>(1);
      for (int j = 0; j < i; ++j)
        A[i * kMaxContact + j] = A[j * kMaxContact + i] = dot<T>(J(r + i) + begin, z(r + j) + begin, end - begin);
    }
    blocks.back().prepare(g);
    r += g;
  }
  M<T> live = ~M<T>{};
  int it = 0;
  for (; it < settings.iterations && any_lane<T>(live); ++it) {
    M<T> moving{};
    int cone = 0;  // the contacts of a FrictionCone swept so far
    for (int r = 0; r < rows.count; ++r) {
      if (const int g = blocks.empty() ? 0 : cone_after_row(r)) {
        // a contact's normal and friction cone rows: one block update
        const ConeBlock<V<T>>& block = blocks[cone++];
        V<T> residual[kMaxContact], p[kMaxContact];
        for (int i = 0; i <= g; ++i) {
          const int x = r + i;
          residual[i] = rows.inv_mass[x] > 0 ? velocity(x) - rows.target[x] + (cfm + rows.cfm[x]) * lambda[x] : V<T>{};
        }
        solve_contact_cone(block, lambda + r, residual, rows.mu + r + 1, s, p);
        for (int i = 0; i <= g; ++i) {
          const int x = r + i;
          const M<T> on = live & rows.active[x] & finite<T>(p[i]) & (p[i] != lambda[x]);
          if (!any_lane<T>(on)) continue;
          apply<T>(z(x), p[i] - lambda[x], on, n, qd);
          moving |= on & moved(x, p[i] - lambda[x]);
          lambda[x] = on ? p[i] : lambda[x];
        }
        r += g;
        continue;
      }
      if (rows.kind[r] == RowKind::FrictionCone) continue;  // (updated with its normal row only)
      // a lane gone non-finite keeps its impulse, so NaN does not spread through the rows
      if (rows.kind[r] != RowKind::FrictionPair) {
        const V<T> sum = lambda[r] + step(r);
        V<T> next;
        if (rows.kind[r] == RowKind::Unilateral) {
          next = project_unilateral(sum);
        } else {
          const V<T> b = rows.kind[r] == RowKind::FrictionOne ? rows.mu[r] * lambda[rows.normal[r]] : rows.bound[r];
          next = project_bounded(sum, b);
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
      const V<T>* j[2] = {J(r), J(r2)};
      V<T> v[2];
      row_velocities<2, T>(j, qd, rows.nonzero_begin[r], rows.nonzero_end[r], rows.zero_begin[r], rows.zero_end[r], v);
      const V<T> l1 = lambda[r] + step_at(r, v[0]), l2 = lambda[r2] + step_at(r2, v[1]);
      V<T> new1, new2;
      project_friction_pair(l1, l2, limit, s, &new1, &new2);
      const M<T> on = live & rows.active[r] & finite<T>(new1) & finite<T>(new2);
      const M<T> on1 = on & (new1 != lambda[r]), on2 = on & (new2 != lambda[r2]);
      if (any_lane<T>(on1 | on2)) apply_pair<T>(z(r), new1 - lambda[r], on1, z(r2), new2 - lambda[r2], on2, n, qd);
      moving |= (on1 & moved(r, new1 - lambda[r])) | (on2 & moved(r2, new2 - lambda[r2]));
      lambda[r] = on1 ? new1 : lambda[r];
      lambda[r2] = on2 ? new2 : lambda[r2];
      ++r;  // the second tangent
    }
    live = moving;
  }
  if (converged) *converged = ~live;
  return it;
}

template int batch_pgs_solve(const BatchRows<float>&, const PgsSettings&, Lanes<float>*, IntLanes<float>*);
template int batch_pgs_solve(const BatchRows<double>&, const PgsSettings&, Lanes<double>*, IntLanes<double>*);

}  // namespace novaphy
