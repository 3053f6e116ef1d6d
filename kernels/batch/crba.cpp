#include "kernels/batch/crba.h"

#include <algorithm>

#include "kernels/batch/lane_math.h"

namespace novaphy {

using namespace lane_math;

template <typename T>
void batch_mass_matrix(const BatchTopology<T>& topo, const BatchParams<T>& params, const V<T>* S, BatchWork<T>& w,
                       V<T>* H) {
  const int n = static_cast<int>(topo.link.size());
  for (int i = n - 1; i > 0; --i) {
    const int p = topo.link[i].parent;
    if (p >= 0)
      for (int m = 0; m < 10; ++m) w.I[10 * p + m] += w.I[10 * i + m];
  }
  for (int i = 0; i < n; ++i) {
    const auto& k = topo.link[i];
    for (int d = 0; d < k.dof; ++d) {
      const int r = k.qd_start + d;
      V<T> F[6];
      apply_inertia<T>(&w.I[10 * i], S + 6 * r, F);
      V<T>* row = H + topo.row_start[r];
      row[r] = dot6<T>(S + 6 * r, F) + params.armature[r];
      for (int p = topo.ancestor_start[r]; p < topo.ancestor_start[r + 1]; ++p) {
        const int j = topo.ancestors[p];
        row[j] = dot6<T>(S + 6 * j, F);
      }
    }
  }
}

template <typename T>
void batch_mass_matrix_gemm(const BatchTopology<T>& topo, const BatchParams<T>& params, const V<T>* S, BatchWork<T>& w,
                            V<T>* H) {
  constexpr int kT = kGemmTile;
  std::fill(H, H + topo.packed_size(), V<T>{});
  V<T>* IJ = w.IJ.data();
  V<T>* zero = IJ + 6 * topo.dof_count;  // the padding column
  std::fill(zero, zero + 6, V<T>{});
  for (size_t i = 0; i < topo.link.size(); ++i) {
    const int* D = topo.link_dofs.data() + topo.link_dof_start[i];
    const int d = topo.link_dof_start[i + 1] - topo.link_dof_start[i];
    if (d == 0) continue;
    // the link's Jacobian columns J_i (columns of S) and I_i J_i, both padded to whole tiles by the zero column
    for (int c = 0; c < d; ++c) apply_inertia<T>(&w.I[10 * i], S + 6 * D[c], IJ + 6 * c);
    for (int rt = 0; rt < d; rt += kT) {
      for (int ct = 0; ct <= rt; ct += kT) {
        // a tile of H in registers: rows rt.., columns ct.., each entry a sum over the 6 spatial components
        const V<T>* s[kT];
        const V<T>* f[kT];
        for (int a = 0; a < kT; ++a) {
          s[a] = rt + a < d ? S + 6 * D[rt + a] : zero;
          f[a] = ct + a < d ? IJ + 6 * (ct + a) : zero;
        }
        V<T> acc[kT][kT] = {};
#pragma GCC unroll 6
        for (int m = 0; m < 6; ++m) {
          V<T> sm[kT], fm[kT];
          for (int a = 0; a < kT; ++a) sm[a] = s[a][m], fm[a] = f[a][m];
          for (int a = 0; a < kT; ++a)
            for (int b = 0; b < kT; ++b) acc[a][b] += sm[a] * fm[b];
        }
        for (int a = 0; a < kT && rt + a < d; ++a) {
          V<T>* row = H + topo.row_start[D[rt + a]];
          for (int b = 0; b < kT && ct + b <= rt + a; ++b) row[D[ct + b]] += acc[a][b];
        }
      }
    }
  }
  for (int k = 0; k < topo.dof_count; ++k) H[topo.row_start[k] + k] += params.armature[k];
}

#define NOVAPHY_INSTANTIATE(T)                                                                                         \
  template void batch_mass_matrix(const BatchTopology<T>&, const BatchParams<T>&, const Lanes<T>*, BatchWork<T>&,      \
                                  Lanes<T>*);                                                                          \
  template void batch_mass_matrix_gemm(const BatchTopology<T>&, const BatchParams<T>&, const Lanes<T>*, BatchWork<T>&, \
                                       Lanes<T>*);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
