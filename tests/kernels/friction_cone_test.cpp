// A contact's friction cone block (kernels/pgs.h: solve_friction_cone, solve_contact_cone) against what MuJoCo's
// elliptic block update should give on random blocks: the unconstrained minimum inside the cone, the block's minimum
// on its surface outside, the convex cone problem's minimum when repeated. The lanes' sweeps against the scalar ones
// over cone rows: batch_pgs_test.cpp.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "kernels/pgs.h"

namespace novaphy {
namespace {

// |(q_i / mu_i)| over a contact's five friction rows
Scalar cone_radius(const Scalar* q, const Scalar* mu) {
  Scalar sum = 0;
  for (int i = 0; i < 5; ++i) sum += (q[i] / mu[i]) * (q[i] / mu[i]);
  return std::sqrt(sum);
}

// solve_friction_cone against what it should give, on random blocks A = J M^-1 J^T + cfm of five rows: within the
// cone, the unconstrained minimiser l = lambda - A^-1 r; outside, a point of the cone's surface no other point of the
// surface beats in A's metric; smoothing 0 clamps each row of l; no normal impulse, no friction; a row of mu 0 at
// most kMinMu times the normal's; a singular block (five rows over two dofs, no cfm) finite and within the cone
TEST(Pgs, AFrictionConeIsMujocosBlockUpdate) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  const Scalar mu[5] = {0.8, 0.8, 0.02, 0.005, 0.005};
  auto radius = [&](const Scalar* q) { return cone_radius(q, mu); };
  int inside = 0, outside = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int dofs = trial % 4 == 3 ? 2 : 6;
    const Scalar cfm = trial % 4 == 3 ? 0 : 0.01;
    const Eigen::MatrixXd Jm = Eigen::MatrixXd::NullaryExpr(5, dofs, [&] { return gauss(rng); });
    const Eigen::MatrixXd Am = Jm * Jm.transpose() + cfm * Eigen::MatrixXd::Identity(5, 5);
    ConeBlock<Scalar> block;  // (its normal row apart: the friction rows' block alone)
    Scalar lambda[5], r[5], p[5];
    Eigen::VectorXd lam(5), res(5);
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) block.A[(i + 1) * kMaxContact + j + 1] = Am(i, j);
      lam[i] = lambda[i] = 0.01 * mu[i] * gauss(rng);
      res[i] = r[i] = 0.02 * mu[i] * gauss(rng) * std::exp(2 * gauss(rng));
    }
    block.prepare(5);
    const Scalar normal = 0.5;
    solve_friction_cone(block, lambda, r, mu, normal, 1.0, p);
    for (int i = 0; i < 5; ++i) ASSERT_TRUE(std::isfinite(p[i])) << "trial " << trial;
    EXPECT_LE(radius(p), normal * (1 + 1e-12)) << "trial " << trial;
    if (dofs == 2) continue;
    const Eigen::VectorXd l = lam - Am.ldlt().solve(res);
    auto cost = [&](const Scalar* q) {
      Eigen::VectorXd d(5);
      for (int i = 0; i < 5; ++i) d[i] = q[i] - l[i];
      return 0.5 * d.dot(Am * d);
    };
    if (radius(l.data()) <= normal) {
      ++inside;
      for (int i = 0; i < 5; ++i) EXPECT_NEAR(p[i], l[i], 1e-12 * (1 + std::abs(l[i]))) << "trial " << trial;
      continue;
    }
    ++outside;
    EXPECT_NEAR(radius(p), normal, 1e-12) << "trial " << trial;
    for (int k = 0; k < 200; ++k) {  // other points of the surface, near p
      Scalar q[5];
      for (int i = 0; i < 5; ++i) q[i] = p[i] + 0.02 * mu[i] * normal * gauss(rng);
      const Scalar scale = normal / radius(q);
      for (Scalar& x : q) x *= scale;
      EXPECT_GE(cost(q), cost(p) * (1 - 1e-9)) << "trial " << trial;
    }
    solve_friction_cone(block, lambda, r, mu, normal, 0.0, p);
    for (int i = 0; i < 5; ++i) EXPECT_NEAR(p[i], std::clamp(l[i], -mu[i] * normal, mu[i] * normal), 1e-12);
    solve_friction_cone(block, lambda, r, mu, Scalar(0), 1.0, p);
    for (int i = 0; i < 5; ++i) EXPECT_EQ(p[i], 0);
    const Scalar no_torsion[5] = {0.8, 0.8, 0, 0.005, 0.005};
    solve_friction_cone(block, lambda, r, no_torsion, normal, 1.0, p);
    EXPECT_LE(std::abs(p[2]), kMinMu * normal * (1 + 1e-12));
  }
  EXPECT_GT(inside, 10);
  EXPECT_GT(outside, 10);
}

// solve_contact_cone repeated on one contact's block (its residuals r = A p + c following its impulses) reaches the
// minimum of 1/2 p^T A p + c^T p over MuJoCo's elliptic cone: no feasible point near it costs less, its friction on
// the cone's surface where it slides (c pulling the friction rows hard), and a separating velocity left on the normal
// row (MuJoCo's relaxed cone: the normal row's own step would leave none). From no normal impulse: the normal row's
// own step first
TEST(Pgs, AContactsConeBlockReachesTheConvexConesMinimum) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss;
  const Scalar mu[5] = {0.5, 0.5, 0.02, 0.01, 0.01};
  auto inside = [&](const Scalar* q) { return q[0] >= 0 && cone_radius(q + 1, mu) <= q[0] * (1 + 1e-12); };
  int sliding = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::MatrixXd Jm = Eigen::MatrixXd::NullaryExpr(6, 6, [&] { return gauss(rng); });
    const Eigen::MatrixXd Am = Jm * Jm.transpose() + 0.05 * Eigen::MatrixXd::Identity(6, 6);
    Eigen::VectorXd c(6);
    c[0] = -1;  // pressed together
    for (int i = 1; i < 6; ++i) c[i] = 3 * mu[i - 1] * gauss(rng);
    ConeBlock<Scalar> block;
    Scalar p[kMaxContact] = {}, r[kMaxContact], next[kMaxContact];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) block.A[i * kMaxContact + j] = Am(i, j);
    block.prepare(5);
    auto residual = [&](const Scalar* q, Scalar* out) {
      for (int i = 0; i < 6; ++i) {
        out[i] = c[i];
        for (int j = 0; j < 6; ++j) out[i] += Am(i, j) * q[j];
      }
    };
    auto cost = [&](const Scalar* q) {
      Scalar x = 0;
      for (int i = 0; i < 6; ++i) {
        x += c[i] * q[i];
        for (int j = 0; j < 6; ++j) x += 0.5 * q[i] * Am(i, j) * q[j];
      }
      return x;
    };
    residual(p, r);
    solve_contact_cone(block, p, r, mu, 1.0, next);
    EXPECT_NEAR(next[0], -c[0] / Am(0, 0), 1e-12);  // no normal impulse yet: the normal's own step
    for (int i = 1; i < 6; ++i) EXPECT_TRUE(std::isfinite(next[i]));
    for (int sweep = 0; sweep < 3000; ++sweep) {
      std::copy(next, next + 6, p);
      residual(p, r);
      solve_contact_cone(block, p, r, mu, 1.0, next);
    }
    ASSERT_TRUE(inside(next)) << "trial " << trial;
    for (int k = 0; k < 300; ++k) {
      Scalar q[6];
      for (int i = 0; i < 6; ++i) q[i] = next[i] + 1e-3 * (i == 0 ? 1 : mu[i - 1]) * gauss(rng);
      if (inside(q)) EXPECT_GE(cost(q), cost(next) - 1e-12) << "trial " << trial;
    }
    residual(next, r);
    if (cone_radius(next + 1, mu) > next[0] * (1 - 1e-9)) {
      ++sliding;
      EXPECT_GT(r[0], 1e-6) << "trial " << trial;
    }
  }
  EXPECT_GT(sliding, 5);
}

}  // namespace
}  // namespace novaphy
