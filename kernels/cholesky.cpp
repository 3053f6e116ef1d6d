#include "kernels/cholesky.h"

#include <cmath>

namespace novaphy {

namespace {

// column j of L from H (columns before j already factored); false if the pivot is not positive
bool factor_column(MatX& H, int j) {
  const int n = static_cast<int>(H.rows());
  Scalar d = H(j, j);
  for (int k = 0; k < j; ++k) d -= H(j, k) * H(j, k);
  if (!(d > 0)) return false;
  const Scalar l_jj = std::sqrt(d);
  H(j, j) = l_jj;
  for (int i = j + 1; i < n; ++i) {
    Scalar x = H(i, j);
    for (int k = 0; k < j; ++k) x -= H(i, k) * H(j, k);
    H(i, j) = x / l_jj;
  }
  return true;
}

// y_i = (b_i - sum_k<i L_ik y_k) / L_ii in place, for one row i
void forward_row(const MatX& L, int i, Scalar* x) {
  Scalar y = x[i];
  for (int k = 0; k < i; ++k) y -= L(i, k) * x[k];
  x[i] = y / L(i, i);
}

void back_substitute(const MatX& L, Scalar* x) {
  for (int i = static_cast<int>(L.rows()) - 1; i >= 0; --i) {
    Scalar y = x[i];
    for (int k = i + 1; k < L.rows(); ++k) y -= L(k, i) * x[k];
    x[i] = y / L(i, i);
  }
}

}  // namespace

int cholesky_factor(MatX& H) {
  for (int j = 0; j < H.rows(); ++j)
    if (!factor_column(H, j)) return j;
  return -1;
}

int cholesky_factor_solve(MatX& H, Scalar* x) {
  // row j of L is complete once column j is factored: substitute it straight away
  for (int j = 0; j < H.rows(); ++j) {
    if (!factor_column(H, j)) return j;
    forward_row(H, j, x);
  }
  back_substitute(H, x);
  return -1;
}

void cholesky_solve(const MatX& L, Scalar* x) {
  for (int i = 0; i < L.rows(); ++i) forward_row(L, i, x);
  back_substitute(L, x);
}

}  // namespace novaphy
