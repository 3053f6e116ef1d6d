// Dense Cholesky factorisation H = L L^T and solves (reference kernel).
#pragma once

#include "kernels/spatial.h"

namespace novaphy {

// factors H in place into its lower triangle; returns -1 on success or the index of the first
// pivot that is not positive (H not positive definite)
int cholesky_factor(MatX& H);

// solves L L^T x = b in place (x holds b on entry), L from cholesky_factor
void cholesky_solve(const MatX& L, Scalar* x);

}  // namespace novaphy
