#include "kernels/cholesky.h"

#include <cmath>

namespace novaphy {

int cholesky_factor(MatX& H) {
  const int n = static_cast<int>(H.rows());
  for (int j = 0; j < n; ++j) {
    Scalar d = H(j, j);
    for (int k = 0; k < j; ++k) d -= H(j, k) * H(j, k);
    if (!(d > 0)) return j;
    const Scalar l_jj = std::sqrt(d);
    H(j, j) = l_jj;
    for (int i = j + 1; i < n; ++i) {
      Scalar x = H(i, j);
      for (int k = 0; k < j; ++k) x -= H(i, k) * H(j, k);
      H(i, j) = x / l_jj;
    }
  }
  return -1;
}

int cholesky_factor_solve(MatX& H, Scalar* x) {
  const int n = static_cast<int>(H.rows());
  for (int j = 0; j < n; ++j) {
    Scalar d = H(j, j);
    for (int k = 0; k < j; ++k) d -= H(j, k) * H(j, k);
    if (!(d > 0)) return j;
    const Scalar l_jj = std::sqrt(d);
    H(j, j) = l_jj;
    // forward substitution of row j, now that it is complete
    Scalar y = x[j];
    for (int k = 0; k < j; ++k) y -= H(j, k) * x[k];
    x[j] = y / l_jj;
    for (int i = j + 1; i < n; ++i) {
      Scalar v = H(i, j);
      for (int k = 0; k < j; ++k) v -= H(i, k) * H(j, k);
      H(i, j) = v / l_jj;
    }
  }
  for (int i = n - 1; i >= 0; --i) {
    Scalar y = x[i];
    for (int k = i + 1; k < n; ++k) y -= H(k, i) * x[k];
    x[i] = y / H(i, i);
  }
  return -1;
}

void cholesky_solve(const MatX& L, Scalar* x) {
  const int n = static_cast<int>(L.rows());
  // forward substitution L y = b
  for (int i = 0; i < n; ++i) {
    Scalar y = x[i];
    for (int k = 0; k < i; ++k) y -= L(i, k) * x[k];
    x[i] = y / L(i, i);
  }
  // back substitution L^T x = y
  for (int i = n - 1; i >= 0; --i) {
    Scalar y = x[i];
    for (int k = i + 1; k < n; ++k) y -= L(k, i) * x[k];
    x[i] = y / L(i, i);
  }
}

}  // namespace novaphy
