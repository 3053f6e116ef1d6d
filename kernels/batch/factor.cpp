#include "kernels/batch/factor.h"

#include <algorithm>

#include "kernels/batch/lane_math.h"

namespace novaphy {

using namespace lane_math;

namespace {

// the most rows of a chain (dofs each the parent of the next) the factor and L x = y take together
constexpr int kChainGroup = 4;

// rows i of the runs, each i taking R rows' outer products in turn: L_i[j] -= L_c[i] L_c[j] for j among i's
// ancestors and i, c = each of the R rows in order (one load and store of L_i[j] for R products)
template <int R, typename T>
void take_outer_products(const BatchTopology<T>& topo, const V<T>* const* Lc, const typename BatchTopology<T>::Run* run,
                         int runs, V<T>* H) {
  for (int r = 0; r < runs; ++r)
    for (int i = run[r].dof; i < run[r].dof + run[r].count; ++i) {
      V<T> l_ci[R];
      for (int t = 0; t < R; ++t) l_ci[t] = Lc[t][i];
      V<T>* Li = H + topo.row_start[i];
      auto entry = [&](int j) {
        V<T> e = Li[j];
        for (int t = 0; t < R; ++t) e -= l_ci[t] * Lc[t][j];
        Li[j] = e;
      };
      for (int s = 0; s < r; ++s)
        for (int j = run[s].dof; j < run[s].dof + run[s].count; ++j) entry(j);
      for (int j = run[r].dof; j <= i; ++j) entry(j);
    }
}

}  // namespace

template <typename T>
IntLanes<T> batch_factor(const BatchTopology<T>& topo, V<T>* H, V<T>* x) {
  // row k of L is final once the rows below it have been folded in: divide it by the pivot, then take
  // its outer product off the rows of its ancestors (all of them ancestors of k too). Rows are taken in
  // groups of up to kChainGroup dofs in a chain (k, k - 1, ..., each the parent dof of the one before:
  // a multi-dof joint, a chain of hinges): each row of the group is finished and folded into the group's
  // rows above it in turn, then all the group's outer products come off the rows of the ancestors in one
  // pass. Each entry takes the same operations in the same order of k as one row at a time would, so the
  // result is the same to the bit; the pass loads and stores an entry once for the group's products
  using Run = typename BatchTopology<T>::Run;
  IntLanes<T> bad = IntLanes<T>{} - 1;
  auto runs_of = [&](int k, const Run** run) {
    *run = topo.ancestor_runs.data() + topo.run_start[k];
    return topo.run_start[k + 1] - topo.run_start[k];
  };
  for (int k = topo.dof_count - 1; k >= 0;) {
    int size = 1;
    while (size < kChainGroup && k - size >= 0 && topo.dof_parent[k - size + 1] == k - size) ++size;
    const V<T>* group[kChainGroup];
    for (int t = 0; t < size; ++t) {
      const int c = k - t;
      V<T>* Lc = H + topo.row_start[c];
      group[t] = Lc;
      const Run* run;
      const int runs = runs_of(c, &run);
      const V<T> d = Lc[c];
      bad = (d > 0) ? bad : IntLanes<T>{} + c;
      const V<T> inv = 1 / lane_sqrt<T>(d);
      Lc[c] = inv;  // the diagonal is kept inverted: solves multiply
      for (int r = 0; r < runs; ++r)
        for (int j = run[r].dof; j < run[r].dof + run[r].count; ++j) Lc[j] *= inv;
      for (int m = c - 1; m > k - size; --m) {  // the group's rows above c: their pivots come next
        V<T>* Lm = H + topo.row_start[m];
        const V<T> l_cm = Lc[m];
        const Run* above;
        const int above_runs = runs_of(m, &above);
        for (int r = 0; r < above_runs; ++r)
          for (int j = above[r].dof; j < above[r].dof + above[r].count; ++j) Lm[j] -= l_cm * Lc[j];
        Lm[m] -= l_cm * Lc[m];
      }
      if (x) {  // L^T y = x: row c of L is final
        const V<T> y = x[c] * inv;
        x[c] = y;
        for (int r = 0; r < runs; ++r)
          for (int j = run[r].dof; j < run[r].dof + run[r].count; ++j) x[j] -= Lc[j] * y;
      }
    }
    const Run* run;
    const int runs = runs_of(k - size + 1, &run);  // the ancestors of the group's top row
    switch (size) {
      case 1: take_outer_products<1>(topo, group, run, runs, H); break;
      case 2: take_outer_products<2>(topo, group, run, runs, H); break;
      case 3: take_outer_products<3>(topo, group, run, runs, H); break;
      default: take_outer_products<kChainGroup>(topo, group, run, runs, H); break;
    }
    k -= size;
  }
  return bad;
}

namespace {

// L x = y for the R rows k, k + 1, ... of a chain (each the parent dof of the next): their sums over the
// first row's ancestors side by side (independent chains of operations, each in its own order), then
// over the group's rows before each
template <int R, typename T>
void solve_lower_group(const BatchTopology<T>& topo, const V<T>* L, int k, V<T>* x) {
  const V<T>* Lt[R];
  V<T> y[R];
  for (int t = 0; t < R; ++t) Lt[t] = L + topo.row_start[k + t], y[t] = x[k + t];
  for (int r = topo.run_start[k]; r < topo.run_start[k + 1]; ++r) {
    const auto& run = topo.ancestor_runs[r];
    for (int j = run.dof; j < run.dof + run.count; ++j) {
      const V<T> x_j = x[j];
      for (int t = 0; t < R; ++t) y[t] -= Lt[t][j] * x_j;
    }
  }
  for (int t = 0; t < R; ++t) {
    for (int s = 0; s < t; ++s) y[t] -= Lt[t][k + s] * x[k + s];
    x[k + t] = y[t] * Lt[t][k + t];
  }
}

}  // namespace

template <typename T>
void batch_solve_lower(const BatchTopology<T>& topo, const V<T>* L, V<T>* x) {
  // row k: x_k = (x_k - the sum over its ancestors j, ascending, of L_kj x_j) / L_kk. A chain's rows (a
  // multi-dof joint, a chain of hinges) go up to four at a time: each row's sum takes the same operations
  // in the same order as alone, so the result is the same to the bit, and the group's sums overlap
  for (int k = 0; k < topo.dof_count;) {
    int size = 1;
    while (size < kChainGroup && k + size < topo.dof_count && topo.dof_parent[k + size] == k + size - 1) ++size;
    switch (size) {
      case 1: solve_lower_group<1>(topo, L, k, x); break;
      case 2: solve_lower_group<2>(topo, L, k, x); break;
      case 3: solve_lower_group<3>(topo, L, k, x); break;
      default: solve_lower_group<kChainGroup>(topo, L, k, x); break;
    }
    k += size;
  }
}

template <typename T>
void batch_solve(const BatchTopology<T>& topo, const V<T>* L, V<T>* x) {
  for (int k = topo.dof_count - 1; k >= 0; --k) {
    const V<T>* Lk = L + topo.row_start[k];
    const V<T> y = x[k] * Lk[k];
    x[k] = y;
    for (int r = topo.run_start[k]; r < topo.run_start[k + 1]; ++r) {
      const auto& run = topo.ancestor_runs[r];
      for (int j = run.dof; j < run.dof + run.count; ++j) x[j] -= Lk[j] * y;
    }
  }
  batch_solve_lower(topo, L, x);
}

namespace {

// batch_solve_many for C right-hand sides: each entry of L loaded once for all of them, each one's sums kept in
// registers (the same operations, in the same order, as subtracting each term from the entry in memory)
template <int C, typename T>
void solve_many(const BatchTopology<T>& topo, const V<T>* L, int end, V<T>* x, int stride) {
  auto y = [&](int r, int k) -> V<T>& { return x[static_cast<size_t>(r) * stride + k]; };
  // L^T y = x, row j from its descendants k, descending (those from `end` on are zero: a dof past `end` has no
  // descendant before it)
  for (int j = end - 1; j >= 0; --j) {
    V<T> sum[C];
    for (int r = 0; r < C; ++r) sum[r] = y(r, j);
    for (int p = topo.descendant_start[j]; p < topo.descendant_start[j + 1]; ++p) {
      const int k = topo.descendants[p];
      if (k >= end) continue;
      const V<T> l = L[topo.row_start[k] + j];
      for (int r = 0; r < C; ++r) sum[r] -= l * y(r, k);
    }
    const V<T> d = L[topo.row_start[j] + j];
    for (int r = 0; r < C; ++r) y(r, j) = sum[r] * d;
  }
  // L y = x, row k from its ancestors, ascending
  for (int k = 0; k < topo.dof_count; ++k) {
    const V<T>* Lk = L + topo.row_start[k];
    V<T> sum[C];
    for (int r = 0; r < C; ++r) sum[r] = y(r, k);
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p) {
      const int i = topo.ancestors[p];
      const V<T> l = Lk[i];
      for (int r = 0; r < C; ++r) sum[r] -= l * y(r, i);
    }
    for (int r = 0; r < C; ++r) y(r, k) = sum[r] * Lk[k];
  }
}

}  // namespace

template <typename T>
void batch_solve_many(const BatchTopology<T>& topo, const V<T>* L, int end, V<T>* x, int count, int stride) {
  constexpr int kMost = 12;  // right-hand sides side by side, their sums in registers
  for (int first = 0; first < count; first += kMost) {
    V<T>* rhs = x + static_cast<size_t>(first) * stride;
    switch (std::min(kMost, count - first)) {
      case 1: solve_many<1>(topo, L, end, rhs, stride); break;
      case 2: solve_many<2>(topo, L, end, rhs, stride); break;
      case 3: solve_many<3>(topo, L, end, rhs, stride); break;
      case 4: solve_many<4>(topo, L, end, rhs, stride); break;
      case 5: solve_many<5>(topo, L, end, rhs, stride); break;
      case 6: solve_many<6>(topo, L, end, rhs, stride); break;
      case 7: solve_many<7>(topo, L, end, rhs, stride); break;
      case 8: solve_many<8>(topo, L, end, rhs, stride); break;
      case 9: solve_many<9>(topo, L, end, rhs, stride); break;
      case 10: solve_many<10>(topo, L, end, rhs, stride); break;
      case 11: solve_many<11>(topo, L, end, rhs, stride); break;
      default: solve_many<kMost>(topo, L, end, rhs, stride); break;
    }
  }
}

template <typename T>
void batch_lane_factor(const BatchTopology<T>& topo, const V<T>* L, int lane, double* out) {
  for (int k = 0; k < topo.packed_size(); ++k) out[k] = L[k][lane];
}

template <typename T>
void batch_solve_packed(const BatchTopology<T>& topo, const double* L, double* x) {
  // L^T y = x: a zero entry stays zero and changes nothing (a contact row's J^T is zero off the path
  // of its link, so another leg's dofs are skipped)
  for (int k = topo.dof_count - 1; k >= 0; --k) {
    if (x[k] == 0) continue;
    const double* Lk = L + topo.row_start[k];
    const double y = x[k] * Lk[k];
    x[k] = y;
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p)
      x[topo.ancestors[p]] -= Lk[topo.ancestors[p]] * y;
  }
  for (int k = 0; k < topo.dof_count; ++k) {
    const double* Lk = L + topo.row_start[k];
    double y = x[k];
    for (int p = topo.ancestor_start[k]; p < topo.ancestor_start[k + 1]; ++p)
      y -= Lk[topo.ancestors[p]] * x[topo.ancestors[p]];
    x[k] = y * Lk[k];
  }
}

#define NOVAPHY_INSTANTIATE(T)                                                                        \
  template IntLanes<T> batch_factor(const BatchTopology<T>&, Lanes<T>*, Lanes<T>*);                   \
  template void batch_solve(const BatchTopology<T>&, const Lanes<T>*, Lanes<T>*);                     \
  template void batch_solve_lower(const BatchTopology<T>&, const Lanes<T>*, Lanes<T>*);               \
  template void batch_solve_many(const BatchTopology<T>&, const Lanes<T>*, int, Lanes<T>*, int, int); \
  template void batch_lane_factor(const BatchTopology<T>&, const Lanes<T>*, int, double*);            \
  template void batch_solve_packed(const BatchTopology<T>&, const double*, double*);
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(double)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
