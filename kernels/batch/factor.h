// Batched LTL factor and solves of H with the tree's sparsity (Featherstone's LTL, RBDA 6.5; twin:
// kernels/cholesky), a world per lane.
#pragma once

#include "kernels/batch/topology.h"

namespace novaphy {

// H = L^T L in place (the diagonal holding 1 / L_kk); with x (not nullptr) solves L^T y = x in the
// same pass (fused). Returns per lane the dof whose pivot was not positive (-1: none)
template <typename T>
IntLanes<T> batch_factor(const BatchTopology<T>& topo, Lanes<T>* H, Lanes<T>* x);

// x = H^-1 x from the factor; after batch_factor(.., x) only the second half (L x = y) is left
template <typename T>
void batch_solve(const BatchTopology<T>& topo, const Lanes<T>* L, Lanes<T>* x);
template <typename T>
void batch_solve_lower(const BatchTopology<T>& topo, const Lanes<T>* L, Lanes<T>* x);
// x_r = H^-1 x_r for `count` right-hand sides x + r stride (a block's rows, up to 12 at a time),
// every lane of each zero at the dofs from `end` on: batch_solve's arithmetic on each (the same values
// for a finite factor), the right-hand sides' independent chains side by side, the zero tail skipped
template <typename T>
void batch_solve_many(const BatchTopology<T>& topo, const Lanes<T>* L, int end, Lanes<T>* x, int count, int stride);

// the factor of the world in one lane, copied out packed in double (packed_size entries), and
// x = H^-1 x with such a copy: the constraint rows' M^-1 J^T, many rows to one copy
template <typename T>
void batch_lane_factor(const BatchTopology<T>& topo, const Lanes<T>* L, int lane, double* out);
template <typename T>
void batch_solve_packed(const BatchTopology<T>& topo, const double* L, double* x);

}  // namespace novaphy
