// The batched kernels against their reference twins (the scalar fk, rnea, crba, mass_matrix_gemm,
// cholesky and integrate kernels in double), lane by lane, each lane a different random state of one random
// tree. Bounds are stated in units of the precision's epsilon times the quantity's largest entry.
#include "kernels/batch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <type_traits>

#include "kernels/cholesky.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/integrate.h"
#include "kernels/rnea.h"
#include "kernels/stream.h"
#include "test_support.h"

namespace novaphy {
namespace {

template <typename T>
constexpr double kEps = std::numeric_limits<T>::epsilon();

// a block of kLanes<T> random states of one articulation, its parameters in lanes, and the
// reference results of each lane
template <typename T>
struct Block {
  using V = Lanes<T>;
  static constexpr int W = kLanes<T>;

  Model model;
  ArticulationView art;
  BatchTopology<T> topo;
  BatchWork<T> w;
  std::vector<V> params, q, qd, S, o, tau, H, H_gemm;
  BatchParams<T> P{};
  std::vector<State> states;
  std::vector<ArticulationScratch> ref;
  bool velocities_differ = false;

  Block(Model model_, std::mt19937& rng) : model(std::move(model_)), art(model.articulation(0)), topo(art) {
    w.resize(topo);
    const int nv = art.dof_count();
    params.resize(batch_param_count(topo));
    P = batch_params(topo, params.data());
    for (int l = 0; l < W; ++l) batch_set_params(topo, art, l, params.data());
    q.resize(art.coord_count()), qd.resize(nv), S.resize(6 * nv), o.resize(3), tau.resize(nv);
    H.resize(topo.packed_size()), H_gemm.resize(topo.packed_size());
    for (int l = 0; l < W; ++l) {
      State s = model.state();
      test::randomize_state(model, s, rng, true);
      // the reference sees the inputs the lanes see: rounded to T
      for (Scalar& v : s.joint_q) v = static_cast<T>(v);
      for (Scalar& v : s.joint_qd) v = static_cast<T>(v);
      for (Scalar& v : s.body_f) v = 0;
      for (int k = 0; k < art.coord_count(); ++k) q[k][l] = static_cast<T>(s.joint_q[art.q_begin() + k]);
      for (int k = 0; k < nv; ++k) qd[k][l] = static_cast<T>(s.joint_qd[art.qd_begin() + k]);
      states.push_back(std::move(s));
      ref.emplace_back();
      ref.back().resize(art);
      forward_kinematics(art, states.back().joint_q.data() + art.q_begin(), ref.back());
      forward_velocity(art, states.back().joint_qd.data() + art.qd_begin(), ref.back());
    }
  }

  // kinematics, bias forces and H of every lane, by the tiled product and by CRBA. The velocities from
  // subspaces kept in registers are those from S, bit for bit (`velocities_differ` otherwise)
  void run() {
    batch_kinematics(topo, q.data(), w, o.data());
    batch_subspace_velocity(topo, o.data(), qd.data(), w);
    const std::vector<V> v = w.v, vrel = w.vrel;
    batch_subspace(topo, w, o.data(), S.data());
    batch_velocity(topo, S.data(), qd.data(), w);
    velocities_differ = std::memcmp(v.data(), w.v.data(), v.size() * sizeof(V)) != 0 ||
                        std::memcmp(vrel.data(), w.vrel.data(), vrel.size() * sizeof(V)) != 0;
    batch_link_inertia(topo, P, o.data(), w);
    V g[3];
    for (int k = 0; k < 3; ++k) g[k] = V{} + static_cast<T>(model.gravity[k]);
    batch_bias(topo, S.data(), g, nullptr, w, tau.data());
    batch_mass_matrix_gemm(topo, P, S.data(), w, H_gemm.data());
    batch_mass_matrix(topo, P, S.data(), w, H.data());
  }
};

// max |a - b| / (eps * max(1, max |b|))
double error_in_eps(const VecX& a, const VecX& b, double eps) {
  const double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
  return (a - b).cwiseAbs().maxCoeff() / (eps * scale);
}

template <typename T>
void expect_twins_agree(double bound) {
  std::mt19937 rng(11);
  double worst_pose = 0, worst_bias = 0, worst_H = 0, worst_gemm = 0, worst_solve = 0;
  for (int trial = 0; trial < 30; ++trial) {
    Block<T> block(test::random_builder_tree(rng, 2 + trial % 9), rng);
    block.run();
    ASSERT_FALSE(block.velocities_differ) << "trial " << trial << ": batch_subspace_velocity against S";
    const ArticulationView& art = block.art;
    const int nv = art.dof_count();
    for (int l = 0; l < Block<T>::W; ++l) {
      ArticulationScratch& s = block.ref[l];
      // link poses
      VecX pose(7 * art.link_count()), pose_ref(7 * art.link_count());
      for (int i = 0; i < art.link_count(); ++i) {
        Quat Q(block.w.Q[4 * i + 3][l], block.w.Q[4 * i][l], block.w.Q[4 * i + 1][l], block.w.Q[4 * i + 2][l]);
        if (Q.coeffs().dot(s.X_world[i].q.coeffs()) < 0) Q.coeffs() *= -1;  // q and -q are one rotation
        pose.segment<7>(7 * i) << block.w.p[3 * i][l], block.w.p[3 * i + 1][l], block.w.p[3 * i + 2][l], Q.x(), Q.y(),
            Q.z(), Q.w();
        pose_ref.segment<7>(7 * i) << s.X_world[i].p, s.X_world[i].q.x(), s.X_world[i].q.y(), s.X_world[i].q.z(),
            s.X_world[i].q.w();
      }
      worst_pose = std::max(worst_pose, error_in_eps(pose, pose_ref, kEps<T>));
      if (nv == 0) continue;
      // bias forces: RNEA at qdd = 0
      VecX bias(nv), bias_ref(nv), zero = VecX::Zero(nv);
      rnea(art, zero.data(), block.model.gravity, nullptr, s, bias_ref.data());
      for (int k = 0; k < nv; ++k) bias[k] = block.tau[k][l];
      worst_bias = std::max(worst_bias, error_in_eps(bias, bias_ref, kEps<T>));
      // H: the ancestor entries against CRBA, which has exact zeros everywhere else
      // and the tiled product against the scalar product of link Jacobians
      crba(art, s);
      ArticulationScratch product = s;
      mass_matrix_gemm(art, product);
      std::vector<Scalar> entries, entries_ref, gemm, gemm_ref;
      for (int i = 0; i < nv; ++i)
        for (int j = 0; j <= i; ++j) {
          bool related = j == i;
          for (int p = block.topo.ancestor_start[i]; p < block.topo.ancestor_start[i + 1]; ++p)
            related |= block.topo.ancestors[p] == j;
          if (!related) {
            EXPECT_EQ(s.H(i, j), 0) << "trial " << trial << " H(" << i << ", " << j << ") of unrelated dofs";
            EXPECT_EQ(block.H_gemm[packed_index(i, j)][l], 0)
                << "trial " << trial << " tiled H(" << i << ", " << j << ") of unrelated dofs";
            continue;
          }
          entries.push_back(block.H[packed_index(i, j)][l]);
          entries_ref.push_back(s.H(i, j));
          gemm.push_back(block.H_gemm[packed_index(i, j)][l]);
          gemm_ref.push_back(product.H(i, j));
        }
      auto map = [](const std::vector<Scalar>& v) { return Eigen::Map<const VecX>(v.data(), v.size()); };
      worst_H = std::max(worst_H, error_in_eps(map(entries), map(entries_ref), kEps<T>));
      worst_gemm = std::max(worst_gemm, error_in_eps(map(gemm), map(gemm_ref), kEps<T>));
    }
    // factor and solve against the reference factor: the residual of H x = b, relative to |H| |x|
    std::vector<Lanes<T>> b(nv), L = block.H;
    for (int k = 0; k < nv; ++k)
      for (int l = 0; l < Block<T>::W; ++l) b[k][l] = static_cast<T>(std::sin(1.0 + k + 3 * l));
    std::vector<Lanes<T>> x = b;
    const IntLanes<T> bad = batch_factor(block.topo, L.data(), x.data());
    batch_solve_lower(block.topo, L.data(), x.data());
    for (int l = 0; l < Block<T>::W && nv > 0; ++l) {
      ASSERT_EQ(bad[l], -1);
      MatX H_ref = block.ref[l].H;
      VecX xl(nv), bl(nv);
      for (int k = 0; k < nv; ++k) xl[k] = x[k][l], bl[k] = b[k][l];
      const double residual = (H_ref * xl - bl).cwiseAbs().maxCoeff();
      worst_solve =
          std::max(worst_solve, residual / (kEps<T> * H_ref.cwiseAbs().maxCoeff() * xl.cwiseAbs().maxCoeff()));
    }
  }
  EXPECT_LT(worst_pose, bound) << "link poses";
  EXPECT_LT(worst_bias, bound) << "bias forces";
  EXPECT_LT(worst_H, bound) << "mass matrix";
  EXPECT_LT(worst_gemm, bound) << "mass matrix by the tiled product";
  EXPECT_LT(worst_solve, bound) << "factor and solve residual";
}

// the streamed rows against their twin, bit for bit: rows shorter and longer than a vector, every count
// of lanes, every alignment of the destination a double can have; nothing outside the rows written
template <typename T>
void expect_streamed_rows_equal_their_twin() {
  constexpr int W = kLanes<T>;
  for (const int count : {1, 2, 3, 5, 7, 8, 9, 13, 16, 17, 78, 91}) {
    std::vector<Lanes<T>> in(count);
    for (int k = 0; k < count; ++k)
      for (int l = 0; l < W; ++l) in[k][l] = static_cast<T>(std::sin(1.0 + k * W + l) * 1e3);
    std::vector<double> expected(count * W + 16), dst(expected.size());
    for (int lanes = 1; lanes <= W; ++lanes)
      for (int offset = 0; offset < 8; ++offset) {
        std::fill(expected.begin(), expected.end(), -1.0);
        std::fill(dst.begin(), dst.end(), -1.0);
        stream_rows_from_lanes_reference<T>(in.data(), count, lanes, expected.data() + offset);
        stream_rows_from_lanes<T>(in.data(), count, lanes, dst.data() + offset);
        stream_fence();
        ASSERT_EQ(std::memcmp(dst.data(), expected.data(), dst.size() * sizeof(double)), 0)
            << count << " numbers of " << lanes << " lanes to offset " << offset;
      }
  }
}

TEST(StreamRowsFromLanes, EqualsItsTwinInBothPrecisions) {
  expect_streamed_rows_equal_their_twin<double>();
  expect_streamed_rows_equal_their_twin<float>();
}

// inside the scope a product below FLT_MIN is zero and a subnormal operand counts as zero; after it,
// the thread's mode is the one it had
TEST(SubnormalsAsZero, FlushesInsideItsScopeAndRestoresTheMode) {
#if !defined(__SSE__)
  GTEST_SKIP() << "subnormals are flushed on x86 only";
#endif
  volatile float tiny = 1e-30f, small = 1e-10f, subnormal = 1e-40f;
  ASSERT_GT(tiny * small, 0.0f);
  {
    const SubnormalsAsZero flush;
    EXPECT_EQ(tiny * small, 0.0f);
    EXPECT_EQ(subnormal * 1.0f, 0.0f);
  }
  EXPECT_GT(tiny * small, 0.0f);
  EXPECT_GT(subnormal * 1.0f, 0.0f);
}

// any_lane against a look at each lane: no lane, each lane alone (with any of its bits), random masks
template <typename T>
void expect_any_lane_is_some_lane_set() {
  constexpr int W = kLanes<T>;
  using Int = std::conditional_t<sizeof(T) == 4, std::int32_t, std::int64_t>;  // IntLanes<T>'s entries
  EXPECT_FALSE(any_lane<T>(IntLanes<T>{}));
  std::mt19937 rng(5);
  for (int l = 0; l < W; ++l)
    for (int bit = 0; bit < 8 * static_cast<int>(sizeof(T)); ++bit) {
      IntLanes<T> m{};
      m[l] = static_cast<Int>(std::make_unsigned_t<Int>{1} << bit);
      ASSERT_TRUE(any_lane<T>(m)) << "lane " << l << " bit " << bit;
    }
  for (int trial = 0; trial < 200; ++trial) {
    IntLanes<T> m{};
    bool some = false;
    for (int l = 0; l < W; ++l) {
      m[l] = rng() % 4 == 0 ? -1 : 0;
      some |= m[l] != 0;
    }
    ASSERT_EQ(any_lane<T>(m), some) << "trial " << trial;
  }
}

TEST(Lanes, AnyLaneIsTrueExactlyWhenSomeLaneIsSetFloat64) { expect_any_lane_is_some_lane_set<double>(); }
TEST(Lanes, AnyLaneIsTrueExactlyWhenSomeLaneIsSetFloat32) { expect_any_lane_is_some_lane_set<float>(); }

// over 30 random trees of 2..10 links (every joint type, rotated frames, offset centres of mass,
// full inertias) the worst seen, in eps times the largest entry (float64 / float32): poses 7 / 9,
// bias forces 32 / 27, H by CRBA 29 / 15, H by the tiled product 30 / 15, solve residual 20 / 8; the
// stated bound is 64
TEST(BatchKernels, Float64LanesEqualTheScalarKernelsWithin64Eps) { expect_twins_agree<double>(64); }
TEST(BatchKernels, Float32LanesEqualTheScalarKernelsWithin64Eps) { expect_twins_agree<float>(64); }

// many right-hand sides solved together equal batch_solve on each: right-hand sides zero in every lane
// from a random dof on, on random trees (so the skipped tail is sometimes empty, sometimes all)
template <typename T>
void expect_many_solves_equal_batch_solve() {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    Block<T> block(test::random_builder_tree(rng, 2 + trial % 9), rng);
    block.run();
    const int nv = block.art.dof_count();
    if (nv == 0) continue;
    std::vector<Lanes<T>> L = block.H;
    ASSERT_EQ(any_lane<T>(batch_factor(block.topo, L.data(), static_cast<Lanes<T>*>(nullptr)) >= 0), false);
    const int end = static_cast<int>(rng() % (nv + 1)), count = 1 + trial * 5 % 14;  // 1 .. 14: past 12 at a time
    std::vector<Lanes<T>> x(count * nv), single(count * nv);
    for (int k = 0; k < end; ++k)
      for (int r = 0; r < count; ++r)
        for (int l = 0; l < Block<T>::W; ++l) x[r * nv + k][l] = static_cast<T>(u(rng));
    single = x;
    batch_solve_many(block.topo, L.data(), end, x.data(), count, nv);
    for (int r = 0; r < count; ++r) batch_solve(block.topo, L.data(), single.data() + r * nv);
    for (int k = 0; k < count * nv; ++k)
      for (int l = 0; l < Block<T>::W; ++l)
        ASSERT_EQ(x[k][l], single[k][l]) << "trial " << trial << " rhs " << k / nv << " dof " << k % nv << " lane "
                                         << l;
  }
}

// batch_factor's arithmetic one row at a time, downwards, on the plain ancestor lists: L, L^T y = x, and
// the lowest dof whose pivot is not positive
template <typename T>
IntLanes<T> factor_row_by_row(const BatchTopology<T>& topo, Lanes<T>* H, Lanes<T>* x) {
  IntLanes<T> bad = IntLanes<T>{} - 1;
  auto at = [&](int i, int j) -> Lanes<T>& { return H[topo.row_start[i] + j]; };
  for (int c = topo.dof_count - 1; c >= 0; --c) {
    const int* a = topo.ancestors.data() + topo.ancestor_start[c];
    const int n = topo.ancestor_start[c + 1] - topo.ancestor_start[c];
    const Lanes<T> d = at(c, c);
    bad = (d > 0) ? bad : IntLanes<T>{} + c;
    const Lanes<T> inv = 1 / lane_sqrt<T>(d);
    at(c, c) = inv;
    for (int s = 0; s < n; ++s) at(c, a[s]) *= inv;
    const Lanes<T> y = x[c] * inv;
    x[c] = y;
    for (int s = 0; s < n; ++s) x[a[s]] -= at(c, a[s]) * y;
    for (int s = 0; s < n; ++s)  // a[s]'s ancestors are a[0 .. s)
      for (int u = 0; u <= s; ++u) at(a[s], a[u]) -= at(c, a[s]) * at(c, a[u]);
  }
  return bad;
}

// batch_factor (rows in chain groups, each group's outer products in one pass) equals the factor one row
// at a time bit for bit, on random trees: L, x and the dof reported for a pivot that is not positive (some
// lanes' diagonals made negative at a random dof: the rows of its ancestors then go NaN)
template <typename T>
void expect_factor_equals_row_by_row() {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 40; ++trial) {
    Block<T> block(test::random_builder_tree(rng, 2 + trial % 12), rng);
    block.run();
    const int nv = block.art.dof_count();
    if (nv == 0) continue;
    std::vector<Lanes<T>> L = block.H, x(nv);
    for (int k = 0; k < nv; ++k)
      for (int l = 0; l < Block<T>::W; ++l) x[k][l] = static_cast<T>(u(rng));
    if (trial % 2 == 1) {
      const int k = static_cast<int>(rng() % nv);
      for (int l = 0; l < Block<T>::W; l += 3) L[block.topo.row_start[k] + k][l] = -1;
    }
    std::vector<Lanes<T>> L_ref = L, x_ref = x;
    const IntLanes<T> bad = batch_factor(block.topo, L.data(), x.data());
    const IntLanes<T> bad_ref = factor_row_by_row(block.topo, L_ref.data(), x_ref.data());
    for (int l = 0; l < Block<T>::W; ++l) EXPECT_EQ(bad[l], bad_ref[l]) << "trial " << trial << " lane " << l;
    // the same bits, or both NaN (a NaN's sign and payload follow the order of an instruction's operands)
    auto same = [](const std::vector<Lanes<T>>& a, const std::vector<Lanes<T>>& b) {
      for (size_t k = 0; k < a.size(); ++k)
        for (int l = 0; l < Block<T>::W; ++l)
          if (std::memcmp(&a[k][l], &b[k][l], sizeof(T)) != 0 && !(std::isnan(a[k][l]) && std::isnan(b[k][l])))
            return false;
      return true;
    };
    EXPECT_TRUE(same(L, L_ref)) << "trial " << trial << ": L";
    EXPECT_TRUE(same(x, x_ref)) << "trial " << trial << ": x";
  }
}

TEST(BatchKernels, Float64FactorEqualsTheFactorOneRowAtATimeBitForBit) { expect_factor_equals_row_by_row<double>(); }
TEST(BatchKernels, Float32FactorEqualsTheFactorOneRowAtATimeBitForBit) { expect_factor_equals_row_by_row<float>(); }

// the runs list each dof's ancestors in order, as maximal stretches of consecutive dofs (the factor and
// the solves walk them in place of the ancestor list)
TEST(BatchTopology, AncestorRunsAreTheAncestorsInMaximalStretches) {
  std::mt19937 rng(29);
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::random_builder_tree(rng, 2 + trial % 9);
    const BatchTopology<double> topo(model.articulation(0));
    for (int k = 0; k < topo.dof_count; ++k) {
      std::vector<int> expanded;
      for (int r = topo.run_start[k]; r < topo.run_start[k + 1]; ++r) {
        const auto& run = topo.ancestor_runs[r];
        ASSERT_GT(run.count, 0);
        if (r > topo.run_start[k]) {
          const auto& before = topo.ancestor_runs[r - 1];
          EXPECT_NE(before.dof + before.count, run.dof) << "trial " << trial << " dof " << k << ": runs not merged";
        }
        for (int j = run.dof; j < run.dof + run.count; ++j) expanded.push_back(j);
      }
      const std::vector<int> ancestors(topo.ancestors.begin() + topo.ancestor_start[k],
                                       topo.ancestors.begin() + topo.ancestor_start[k + 1]);
      EXPECT_EQ(expanded, ancestors) << "trial " << trial << " dof " << k;
    }
  }
}

TEST(BatchKernels, Float64ManySolvesEqualBatchSolve) { expect_many_solves_equal_batch_solve<double>(); }
TEST(BatchKernels, Float32ManySolvesEqualBatchSolve) { expect_many_solves_equal_batch_solve<float>(); }

template <typename T>
void expect_integration_agrees() {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    Block<T> block(test::random_builder_tree(rng, 2 + trial), rng);
    const ArticulationView& art = block.art;
    std::vector<Lanes<T>> q_next(art.coord_count());
    const T dt = static_cast<T>(0.01);
    batch_integrate(block.topo, block.q.data(), block.qd.data(), dt, q_next.data());
    for (int l = 0; l < Block<T>::W; ++l) {
      const State& s = block.states[l];
      VecX next(art.coord_count()), ref(art.coord_count());
      integrate_joints(art, s.joint_q.data() + art.q_begin(), s.joint_qd.data() + art.qd_begin(), dt, ref.data());
      for (int k = 0; k < art.coord_count(); ++k) next[k] = q_next[k][l];
      EXPECT_LT(error_in_eps(next, ref, kEps<T>), 16) << "trial " << trial << " lane " << l;
    }
  }
}

TEST(BatchKernels, Float64IntegrationEqualsTheScalarKernelWithin16Eps) { expect_integration_agrees<double>(); }
TEST(BatchKernels, Float32IntegrationEqualsTheScalarKernelWithin16Eps) { expect_integration_agrees<float>(); }

template <typename T>
void expect_sincos_within(double range, double ulps) {
  using V = Lanes<T>;
  double worst = 0;
  for (int k = 0; k < 20000; ++k) {
    V x, s, c;
    for (int l = 0; l < kLanes<T>; ++l) x[l] = static_cast<T>(range * std::sin(0.37 * (k * kLanes<T> + l)));
    lane_sincos<T>(x, &s, &c);
    for (int l = 0; l < kLanes<T>; ++l) {
      const long double xs = x[l];
      // error in units of the precision's epsilon (absolute: sin and cos are at most 1)
      worst = std::max(worst, static_cast<double>(std::abs(s[l] - std::sin(xs)) / kEps<T>));
      worst = std::max(worst, static_cast<double>(std::abs(c[l] - std::cos(xs)) / kEps<T>));
    }
  }
  EXPECT_LT(worst, ulps);
}

// worst seen 0.76 eps in both precisions
TEST(LaneSinCos, Float64WithinOneEpsUpToTenThousandRadians) { expect_sincos_within<double>(1e4, 1); }
TEST(LaneSinCos, Float32WithinOneEpsUpToAThousandRadians) { expect_sincos_within<float>(1e3, 1); }

}  // namespace
}  // namespace novaphy
