// The lane PGS (kernels/batch/pgs) alone on rows shaped like a standing quadruped's in one block: 18 dofs, a
// dry-friction row on each of the 12 leg joints (J = e_k), and four feet in contact with condim 6 (a normal row,
// the sliding pair, the torsional row, the rolling pair), J nonzero on the base and the foot's leg; every lane has
// every row; 20 sweeps (no tolerance). Arguments: precision (0 float64, 1 float32), feet in contact (0-4: the
// rows' bytes against the L1 cache).
//   novaphy_bench_pgs
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "kernels/batch/pgs.h"

namespace novaphy {
namespace {

constexpr int kDofs = 18;

template <typename T>
struct QuadrupedRows {
  using V = Lanes<T>;
  std::vector<RowKind> kind;
  std::vector<int> normal, begin, end, zero_begin, zero_end;
  std::vector<V> J, z, target, cfm, mu, bound, inv_mass, lambda, lambda0, qd, qd0;
  std::vector<IntLanes<T>> active;

  explicit QuadrupedRows(int feet = 4) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    auto row = [&](RowKind k, int n, int b, int e) {
      kind.push_back(k), normal.push_back(n), begin.push_back(b), end.push_back(e);
      // the other legs' quads between the base's dofs and the foot's leg
      zero_begin.push_back(k == RowKind::Bounded ? 0 : 8), zero_end.push_back(k == RowKind::Bounded ? 0 : (e - 3) & ~3);
    };
    for (int k = 6; k < kDofs; ++k) row(RowKind::Bounded, -1, k, k + 1);
    for (int foot = 0; foot < feet; ++foot) {
      const int r = static_cast<int>(kind.size()), leg_end = 9 + 3 * foot;
      row(RowKind::Unilateral, -1, 0, leg_end);
      row(RowKind::FrictionPair, r, 0, leg_end);
      row(RowKind::FrictionPair, r, 0, leg_end);
      row(RowKind::FrictionOne, r, 0, leg_end);
      row(RowKind::FrictionPair, r, 0, leg_end);
      row(RowKind::FrictionPair, r, 0, leg_end);
    }
    const int rows = static_cast<int>(kind.size());
    J.resize(rows * kDofs), z.resize(rows * kDofs);
    for (auto* x : {&target, &cfm, &mu, &bound, &inv_mass, &lambda}) x->resize(rows);
    qd.resize(kDofs);
    active.resize(rows);
    for (int l = 0; l < kLanes<T>; ++l) {
      Eigen::MatrixXd A = Eigen::MatrixXd::NullaryExpr(kDofs, kDofs, [&] { return u(rng); });
      const Eigen::LLT<Eigen::MatrixXd> llt(A * A.transpose() + kDofs * Eigen::MatrixXd::Identity(kDofs, kDofs));
      for (int k = 0; k < kDofs; ++k) qd[k][l] = static_cast<T>(u(rng));
      for (int r = 0; r < rows; ++r) {
        Eigen::VectorXd j = Eigen::VectorXd::Zero(kDofs);
        if (kind[r] == RowKind::Bounded) {
          j[begin[r]] = 1;
        } else {
          for (int k = 0; k < 6; ++k) j[k] = u(rng);
          for (int k = end[r] - 3; k < end[r]; ++k) j[k] = u(rng);
        }
        const Eigen::VectorXd x = llt.solve(j);
        for (int k = 0; k < kDofs; ++k)
          J[r * kDofs + k][l] = static_cast<T>(j[k]), z[r * kDofs + k][l] = static_cast<T>(x[k]);
        active[r][l] = -1;
        target[r][l] = kind[r] == RowKind::Unilateral ? static_cast<T>(0.5 + 0.2 * u(rng)) : 0;
        cfm[r][l] = static_cast<T>(0.01);
        mu[r][l] = static_cast<T>(kind[r] == RowKind::FrictionOne ? 0.02 : 0.8);
        bound[r][l] = static_cast<T>(0.002);
        lambda[r][l] = 0;
      }
    }
    lambda0 = lambda, qd0 = qd;
  }

  BatchRows<T> rows() {
    BatchRows<T> b;
    b.count = static_cast<int>(kind.size());
    b.dofs = kDofs;
    b.kind = kind.data();
    b.normal = normal.data();
    b.J = J.data();
    b.nonzero_begin = begin.data();
    b.nonzero_end = end.data();
    b.zero_begin = zero_begin.data();
    b.zero_end = zero_end.data();
    b.MinvJT = z.data();
    b.target = target.data();
    b.cfm = cfm.data();
    b.mu = mu.data();
    b.bound = bound.data();
    b.active = active.data();
    b.inv_mass = inv_mass.data();
    b.lambda = lambda.data();
    return b;
  }
};

template <typename T>
void sweeps(benchmark::State& bm) {
  QuadrupedRows<T> p(static_cast<int>(bm.range(1)));
  PgsSettings settings;
  settings.cfm = 1e-6;
  for (auto _ : bm) {
    p.lambda = p.lambda0, p.qd = p.qd0;
    benchmark::DoNotOptimize(batch_pgs_solve(p.rows(), settings, p.qd.data()));
    benchmark::ClobberMemory();
  }
  bm.counters["rows"] = static_cast<double>(p.kind.size());
  bm.counters["ns_per_row_sweep"] =
      benchmark::Counter(static_cast<double>(p.kind.size()) * settings.iterations,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_PgsQuadruped(benchmark::State& bm) {
  if (bm.range(0) == 1)
    sweeps<float>(bm);
  else
    sweeps<double>(bm);
}
BENCHMARK(BM_PgsQuadruped)->ArgsProduct({{0, 1}, {0, 1, 2, 3, 4}});

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
