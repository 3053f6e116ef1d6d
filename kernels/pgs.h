// Projected Gauss-Seidel over velocity constraint rows in joint space (sequential impulses,
// Catto 2005; Featherstone RBDA chapter 11 for the joint-space form). A row acts on the dofs of
// one or two articulations through J (its Jacobian row over each side's dofs) and M^-1 J^T.
#pragma once

#include <vector>

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

// two unit tangents completing a contact normal n to a right-handed frame (Frisvad's construction)
void contact_tangents(const Vec3& n, Vec3* t1, Vec3* t2);

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
