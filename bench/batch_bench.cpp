// The batched kernels on one core: the mass matrix (link inertias, then CRBA's composite inertias
// or use_tile_gemm's tiled product sum J_i^T I_i J_i) + the fused L^T L factor and solve, per scene
// x precision x worlds, in GFLOP/s from the flop model below and as a fraction of this core's FP32
// FMA peak, which BM_FmaPeak measures in the same program.
//   novaphy_bench_batch --benchmark_format=json
// Arguments of BM_CrbaCholesky: scene (0 chain15, 1 quadruped, 2 humanoid), precision (0 float64,
// 1 float32), worlds, kernel (0 CRBA, 1 tiled product). items_per_second is worlds per second.
#include <benchmark/benchmark.h>

#include <chrono>
#include <random>
#include <vector>

#include "engine/import/mjcf_import.h"
#include "kernels/batch.h"

namespace novaphy {
namespace {

const char* const kScenes[] = {NOVAPHY_SCENE_DIR "/chain15.xml", NOVAPHY_SCENE_DIR "/quadruped.xml",
                               NOVAPHY_HUMANOID_XML};

// FP32 FMA peak of one core in GFLOP/s, measured once: 12 independent accumulators of one vector
// register each (enough to cover the FMA latency on two pipes), 2 flops per lane per FMA
double fma_peak() {
  static const double peak = [] {
    using V = Lanes<float>;
    constexpr int kAccumulators = 12, kInner = 20'000'000;
    V acc[kAccumulators];
    for (int k = 0; k < kAccumulators; ++k) acc[k] = V{} + 0.001f * static_cast<float>(k);
    V a = V{} + 0.999999f, b = V{} + 1e-7f;
    benchmark::DoNotOptimize(a);
    benchmark::DoNotOptimize(b);
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < kInner; ++i)
      for (int k = 0; k < kAccumulators; ++k) acc[k] = acc[k] * a + b;
    benchmark::DoNotOptimize(acc);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return 2.0 * kLanes<float> * kAccumulators * kInner / seconds * 1e-9;
  }();
  return peak;
}

void BM_FmaPeak(benchmark::State& bm) {
  for (auto _ : bm) benchmark::DoNotOptimize(fma_peak());
  bm.counters["GFLOPs"] = fma_peak();
}
BENCHMARK(BM_FmaPeak);

// flops per world of link inertias + CRBA or the tiled product + fused factor and solve, counted
// from the kernels' arithmetic (an FMA is two flops; sqrt and division one each; the tiled
// product's padding to whole tiles and the upper halves of its diagonal tiles not counted)
template <typename T>
double mass_cholesky_flops(const BatchTopology<T>& topo, bool tile_gemm) {
  double flops = 0;
  const int n = static_cast<int>(topo.link.size());
  flops += n * 123.0;  // batch_link_inertia: R c + p - o (21), R I R^T (75), h (3), J (24)
  if (tile_gemm) {
    for (int i = 0; i < n; ++i) {
      const int d = topo.link_dof_start[i + 1] - topo.link_dof_start[i];
      flops += 42.0 * d + 12.0 * d * (d + 1) / 2;  // I_i J_i, then the lower triangle of J_i^T (I_i J_i)
    }
    flops += topo.dof_count;  // armature
  } else {
    for (const auto& L : topo.link) flops += L.parent >= 0 ? 10 : 0;  // composite inertias
  }
  for (int k = 0; k < topo.dof_count; ++k) {
    const int m = topo.ancestor_start[k + 1] - topo.ancestor_start[k];
    if (!tile_gemm) flops += 42 + 11.0 * (m + 1) + 1;  // I s, s . (I s) for k and its ancestors, armature
    flops += 2 + m + m * (m + 1);                      // sqrt and reciprocal, row scaling, outer-product update
    flops += 1 + 2.0 * m;                              // fused L^T y = x
    flops += 1 + 2.0 * m;                              // L x = y
  }
  return flops;
}

template <typename T>
void mass_cholesky(benchmark::State& bm) {
  using V = Lanes<T>;
  constexpr int W = kLanes<T>;
  ModelBuilder builder;
  import_mjcf(builder, kScenes[bm.range(0)]);
  const Model model = builder.finalize();
  const ArticulationView art = model.articulation(0);
  const BatchTopology<T> topo(art);
  const int worlds = static_cast<int>(bm.range(2)), blocks = (worlds + W - 1) / W;
  const bool tile_gemm = bm.range(3) == 1;
  const int nv = art.dof_count();
  // per block: parameters, coordinates, kinematics, S, o, H and the right-hand side
  std::vector<V> params(batch_param_count(topo)), q(static_cast<size_t>(blocks) * art.coord_count());
  std::vector<BatchWork<T>> work(blocks);
  std::vector<V> S(static_cast<size_t>(blocks) * 6 * nv), o(3 * blocks),
      H(static_cast<size_t>(blocks) * topo.packed_size());
  std::vector<V> x(static_cast<size_t>(blocks) * nv);
  const BatchParams<T> P = batch_params(topo, params.data());
  for (int l = 0; l < W; ++l) batch_set_params(topo, art, l, params.data());
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> angle(-1, 1);
  for (int b = 0; b < blocks; ++b) {
    work[b].resize(topo);
    V* qb = q.data() + static_cast<size_t>(b) * art.coord_count();
    for (int c = 0; c < art.coord_count(); ++c)
      for (int l = 0; l < W; ++l) qb[c][l] = static_cast<T>(model.joint_q0[c] + 0.3 * angle(rng));
    batch_kinematics(topo, qb, work[b], &o[3 * b]);
    batch_subspace(topo, work[b], &o[3 * b], &S[static_cast<size_t>(b) * 6 * nv]);
  }
  for (auto _ : bm) {
    for (int b = 0; b < blocks; ++b) {
      V* Hb = &H[static_cast<size_t>(b) * topo.packed_size()];
      V* xb = &x[static_cast<size_t>(b) * nv];
      for (int k = 0; k < nv; ++k) xb[k] = V{} + 1;
      batch_link_inertia(topo, P, &o[3 * b], work[b]);
      if (tile_gemm)
        batch_mass_matrix_gemm(topo, P, &S[static_cast<size_t>(b) * 6 * nv], work[b], Hb);
      else
        batch_mass_matrix(topo, P, &S[static_cast<size_t>(b) * 6 * nv], work[b], Hb);
      benchmark::DoNotOptimize(batch_factor(topo, Hb, xb));
      batch_solve_lower(topo, Hb, xb);
    }
    benchmark::ClobberMemory();
  }
  const double flops = mass_cholesky_flops(topo, tile_gemm) * blocks * W;
  bm.SetItemsProcessed(bm.iterations() * worlds);
  bm.counters["GFLOPs"] =
      benchmark::Counter(flops * 1e-9 * static_cast<double>(bm.iterations()), benchmark::Counter::kIsRate);
  bm.counters["flops_per_world"] = mass_cholesky_flops(topo, tile_gemm);
  bm.counters["fma_peak_GFLOPs"] = fma_peak();  // the report divides GFLOPs by it
  bm.counters["scene"] = static_cast<double>(bm.range(0));
  bm.counters["precision"] = static_cast<double>(bm.range(1));
  bm.counters["worlds"] = worlds;
  bm.counters["kernel"] = static_cast<double>(tile_gemm);
}

void BM_CrbaCholesky(benchmark::State& bm) {
  if (bm.range(1) == 1)
    mass_cholesky<float>(bm);
  else
    mass_cholesky<double>(bm);
}
BENCHMARK(BM_CrbaCholesky)
    ->ArgsProduct({{0, 1, 2}, {0, 1}, {kLanes<float>, 64, 1024, 4096}, {0, 1}})
    ->ArgNames({"scene", "precision", "worlds", "kernel"});

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
