// Dense Cholesky factorisation H = L L^T and solves (reference kernel).
#pragma once

#include "kernels/spatial.h"

namespace novaphy {

// factors H in place into its lower triangle; returns -1 on success or the index of the first
// pivot that is not positive (H not positive definite)
int cholesky_factor(MatX& H);

// solves L L^T x = b in place (x holds b on entry), L from cholesky_factor
void cholesky_solve(const MatX& L, Scalar* x);

// factor and forward substitution in one pass over the columns, then back substitution:
// H holds L and x the solution afterwards; returns as cholesky_factor
int cholesky_factor_solve(MatX& H, Scalar* x);

}  // namespace novaphy
