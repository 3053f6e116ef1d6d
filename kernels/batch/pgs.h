// Projected Gauss-Seidel on lanes: the sweeps of kernels/pgs.h (its reference twin) over a block's
// rows, one world per lane. Every lane of a block has the same row slots; a slot a world does not
// have is masked off in that lane (its impulse stays 0 and its velocity untouched, bit for bit), so
// a world's result does not depend on the other worlds of its block.
#pragma once

#include "kernels/lanes.h"
#include "kernels/pgs.h"

namespace novaphy {

// a block's rows: per row its kind (the same in every lane) and per lane its numbers
template <typename T>
struct BatchRows {
  int count = 0;                  // rows
  int dofs = 0;                   // the length of each row of J and M^-1 J^T
  const RowKind* kind = nullptr;  // [row] a FrictionPair row is followed by its second tangent
  const int* normal = nullptr;    // [row] FrictionPair, FrictionOne, FrictionCone: the row holding the normal impulse
  const Lanes<T>* J = nullptr;    // [row][dof]
  // [row]: J is +-0 in every lane outside dofs nonzero_begin[r] .. nonzero_end[r] - 1, which J qd skips
  const int* nonzero_begin = nullptr;
  const int* nonzero_end = nullptr;
  // [row]: and outside zero_begin[r] .. zero_end[r] - 1, both multiples of 4, which J qd skips too (equal: none
  // skipped). A FrictionPair row's second tangent has the first's
  const int* zero_begin = nullptr;
  const int* zero_end = nullptr;
  const Lanes<T>* MinvJT = nullptr;     // [row][dof]
  const Lanes<T>* target = nullptr;     // [row] the velocity J qd the row drives towards
  const Lanes<T>* cfm = nullptr;        // [row] its own constraint force mixing, beyond the settings' cfm
  const Lanes<T>* mu = nullptr;         // [row] FrictionPair, FrictionOne, FrictionCone: friction coefficient
  const Lanes<T>* bound = nullptr;      // [row] Bounded: the largest |impulse|
  const IntLanes<T>* active = nullptr;  // [row] -1 in the lanes that have the row, 0 elsewhere
  Lanes<T>* inv_mass = nullptr;         // [row] out: 1 / (J M^-1 J^T + settings' cfm + cfm), 0 for a row of no mass
  Lanes<T>* lambda = nullptr;           // [row] in: the warm start (not yet applied); out: the impulse
};

// the rows' effective masses, the warm start applied to qd [dof], then the sweeps in row order:
// the same steps, per lane, as the solver's scalar path (finish_row, apply_impulse, pgs_solve); with a
// tolerance, each lane stops where pgs_solve would stop it; *converged (if given): -1 in the lanes whose sweeps
// stopped at one that moved no row beyond the tolerance, 0 where they ran out. Returns the sweeps run (the most
// of any lane)
template <typename T>
int batch_pgs_solve(const BatchRows<T>& rows, const PgsSettings& settings, Lanes<T>* qd,
                    IntLanes<T>* converged = nullptr);

}  // namespace novaphy
