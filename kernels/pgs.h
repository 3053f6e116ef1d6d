// Projected Gauss-Seidel over velocity constraint rows in joint space (sequential impulses,
// Catto 2005; Featherstone RBDA chapter 11 for the joint-space form). A row acts on the dofs of
// one or two articulations through J (its Jacobian row over each side's dofs) and M^-1 J^T.
#pragma once

#include <vector>

#include "kernels/number.h"
#include "kernels/spatial.h"

namespace novaphy {

// Unilateral: impulse >= 0 (a contact's normal, a limit); FrictionPair: two tangent rows bounded together by
// mu times their normal row's impulse (sliding, or rolling about the tangents); Bounded: |impulse| <= bound (a
// joint's dry friction); FrictionOne: |impulse| <= mu times its normal row's impulse (torsional friction)
enum class RowKind : int { Unilateral = 0, FrictionPair = 1, Bounded = 2, FrictionOne = 3 };

struct PgsRow {
  RowKind kind = RowKind::Unilateral;  // a FrictionPair row is followed by its second tangent row
  int side_count = 1;
  int dof_begin[2] = {0, 0};  // first dof of each side in the global velocity vector
  int dof_count[2] = {0, 0};
  int pool[2] = {0, 0};  // offset of each side's J and M^-1 J^T in the pools
  Scalar cfm = 0;        // the row's own constraint force mixing, beyond the settings' (a soft contact's)
  Scalar inv_mass = 0;   // 1 / (J M^-1 J^T + settings.cfm + cfm)
  Scalar target = 0;     // the velocity J qd the row drives towards
  Scalar lambda = 0;     // accumulated impulse
  int normal = -1;       // FrictionPair, FrictionOne: the row holding the normal impulse
  Scalar mu = 0;         // FrictionPair, FrictionOne: friction coefficient
  Scalar bound = 0;      // Bounded: the largest |impulse|
};

struct PgsSettings {
  int iterations = 20;  // sweeps at most
  Scalar cfm = 0;
  Scalar friction_smoothing = 1;  // 0: box friction per tangent, 1: circular cone, between: blend
  // the sweeps stop early once one sweep moved no row's impulse by more than tolerance / (J M^-1 J^T),
  // i.e. no row's own velocity by more than tolerance (m/s, rad/s); 0: once one sweep moved no impulse
  // at all (a fixed point: the sweeps left would repeat it bit for bit)
  Scalar tolerance = 0;
};

// a contact's frame d [9] from its unit normal n [3]: the normal, then two unit tangents t1 and t2 completing it to
// a right-handed frame (Frisvad's construction), over the number type (kernels/number.h: one contact, or one a
// lane). A lane with n = 0 gets finite numbers
template <typename V>
inline void contact_frame(const V* n, V* d) {
  const V sign = unit_sign(n[2]);
  const V a = Element<V>(-1) / (sign + n[2]), b = n[0] * n[1] * a;
  for (int m = 0; m < 3; ++m) d[m] = n[m];
  d[3] = 1 + sign * n[0] * n[0] * a;
  d[4] = sign * b;
  d[5] = -sign * n[0];
  d[6] = b;
  d[7] = sign + n[1] * n[1] * a;
  d[8] = -n[1];
}

// contact_frame's tangents of the normal n
void contact_tangents(const Vec3& n, Vec3* t1, Vec3* t2);

// a row's 1 / (J M^-1 J^T + cfm) from jmj = J M^-1 J^T and its cfm (the settings' and its own), 0 for a row of no
// mass (at most 1e-12): the effective mass both sweeps scale a row's velocity error by
template <typename V>
inline V row_inv_mass(const V& jmj, const V& cfm) {
  const V w = jmj + cfm;
  return select<V>(w > Element<V>(1e-12), 1 / w, V{});
}

// ---- a row's impulse projected onto its bounds in a sweep, over the number type: one row (pgs_solve) or a row
// of a block's lanes (batch_pgs_solve). A NaN stays NaN or becomes a bound; the sweeps skip a non-finite impulse

// Unilateral: at least 0
template <typename V>
inline V project_unilateral(const V& impulse) {
  return select<V>(impulse > 0, impulse, V{});
}

// Bounded and FrictionOne: within [-bound, bound]
template <typename V>
inline V project_bounded(const V& impulse, const V& bound) {
  return select<V>(impulse < -bound, -bound, select<V>(impulse > bound, bound, impulse));
}

// FrictionPair: the two tangents' impulses l1, l2 within limit (mu times the normal's impulse), *p1 and *p2: each
// clamped to the limit (a box, smoothing 0), the pair scaled into the disk of that radius (1), or a blend
template <typename V>
inline void project_friction_pair(const V& l1, const V& l2, const V& limit, Element<V> smoothing, V* p1, V* p2) {
  const V box1 = project_bounded(l1, limit), box2 = project_bounded(l2, limit);
  // (not hypot: its guard against overflow costs more than the rest of the pair's update)
  const V norm = root(l1 * l1 + l2 * l2);
  const V scale = select<V>(norm > limit, limit / norm, splat<V>(1));
  *p1 = (1 - smoothing) * box1 + smoothing * scale * l1;
  *p2 = (1 - smoothing) * box2 + smoothing * scale * l2;
}

// J qd of one row
Scalar row_velocity(const PgsRow& row, const std::vector<Scalar>& J, const Scalar* qd);

// qd += M^-1 J^T * impulse for one row
void apply_impulse(const PgsRow& row, const std::vector<Scalar>& MinvJT, Scalar impulse, Scalar* qd);

// sweeps the rows order[0 .. count) in that order (a friction pair's second row follows its first)
// inputs:  rows with lambda as the warm start (already applied to qd), the pools
// outputs: rows[].lambda, qd; *converged (if given): whether the sweeps stopped at one that moved no row beyond
//          the tolerance (false where they ran out); returns the sweeps run
int pgs_solve(std::vector<PgsRow>& rows, const int* order, int count, const std::vector<Scalar>& J,
              const std::vector<Scalar>& MinvJT, const PgsSettings& settings, Scalar* qd, bool* converged = nullptr);

}  // namespace novaphy
