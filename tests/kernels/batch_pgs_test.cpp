// Lane PGS (kernels/batch/pgs) against its reference twin, the scalar pgs_solve in double, lane by
// lane: each lane its own random rows, some of them absent in some lanes. Bounds are in units of the
// precision's epsilon times the largest entry: 64 eps (the worst seen, float32 over 15 sweeps, is 7 eps).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

#include "kernels/batch/pgs.h"

namespace novaphy {
namespace {

template <typename T>
constexpr double kEps = std::numeric_limits<T>::epsilon();

constexpr int kDofs = 11;

// the rows of a block: their kinds and the row of each friction row's normal
struct Layout {
  int count;
  const RowKind* kind;
  const int* normal;
};
// two limit-like rows, then two contacts (a normal row, then its friction pair)
const RowKind kPairKind[] = {RowKind::Unilateral,   RowKind::Unilateral, RowKind::Unilateral,   RowKind::FrictionPair,
                             RowKind::FrictionPair, RowKind::Unilateral, RowKind::FrictionPair, RowKind::FrictionPair};
const int kPairNormal[] = {-1, -1, 2, 2, 2, 5, 5, 5};
constexpr Layout kPairs{8, kPairKind, kPairNormal};
constexpr int kRows = 8;
// a limit-like row, a contact of condim 6 (a normal, five rows in one cone), one of condim 3 in a cone (as the
// blocks lay it out where another contact has condim 6), a limit-like row
constexpr RowKind U = RowKind::Unilateral, C = RowKind::FrictionCone;
const RowKind kConeKind[] = {U, U, C, C, C, C, C, U, C, C, U};
const int kConeNormal[] = {-1, -1, 1, 1, 1, 1, 1, -1, 7, 7, -1};
constexpr Layout kCones{11, kConeKind, kConeNormal};

// a block of random rows: per lane an SPD mass matrix, J, M^-1 J^T, targets, warm starts and
// friction; lane l lacks row r where absent(l, r)
template <typename T>
struct Problem {
  using V = Lanes<T>;
  static constexpr int W = kLanes<T>;
  std::vector<V> J, z, target, cfm, mu, inv_mass, lambda, qd;  // cfm: a soft row's own, on every other row
  std::vector<IntLanes<T>> active;
  // every row dense but the first, nonzero on dofs 2, 3 and 9, and the first contact's, on 0, 1 and 8 .. 10: the
  // quads 4 .. 7 between them skipped
  std::vector<int> nonzero_begin, nonzero_end, zero_begin, zero_end;

  Layout layout;

  Problem(std::mt19937& rng, bool (*absent)(int lane, int row), const Layout& layout = kPairs)
      : J(layout.count * kDofs),
        z(layout.count * kDofs),
        target(layout.count),
        cfm(layout.count),
        mu(layout.count),
        inv_mass(layout.count),
        lambda(layout.count),
        qd(kDofs),
        active(layout.count),
        layout(layout) {
    std::uniform_real_distribution<double> u(-1, 1);
    for (int r = 0; r < layout.count; ++r) {
      const bool skips = r == 0 || (r >= 2 && r <= 4);
      nonzero_begin.push_back(r == 0 ? 2 : 0);
      nonzero_end.push_back(r == 0 ? 10 : kDofs);
      zero_begin.push_back(skips ? 4 : 0);
      zero_end.push_back(skips ? 8 : 0);
    }
    auto nonzero = [](int r, int k) {
      if (r == 0) return k == 2 || k == 3 || k == 9;
      if (r >= 2 && r <= 4) return k <= 1 || k >= 8;
      return true;
    };
    for (int l = 0; l < W; ++l) {
      Eigen::MatrixXd A = Eigen::MatrixXd::NullaryExpr(kDofs, kDofs, [&] { return u(rng); });
      const Eigen::MatrixXd M = A * A.transpose() + Eigen::MatrixXd::Identity(kDofs, kDofs);
      const Eigen::LLT<Eigen::MatrixXd> llt(M);
      for (int k = 0; k < kDofs; ++k) qd[k][l] = static_cast<T>(u(rng));
      for (int r = 0; r < layout.count; ++r) {
        const bool on = !absent(l, r);
        active[r][l] = on ? -1 : 0;
        Eigen::VectorXd j(kDofs);
        for (int k = 0; k < kDofs; ++k) j[k] = on && nonzero(r, k) ? static_cast<T>(u(rng)) : 0;
        const Eigen::VectorXd x = llt.solve(j);
        for (int k = 0; k < kDofs; ++k) {
          J[r * kDofs + k][l] = static_cast<T>(j[k]);
          z[r * kDofs + k][l] = static_cast<T>(x[k]);
        }
        target[r][l] = on ? static_cast<T>(u(rng)) : 0;
        cfm[r][l] = on && r % 2 == 1 ? static_cast<T>(0.2 * (1 + u(rng))) : 0;
        lambda[r][l] =
            on ? static_cast<T>(layout.kind[r] == RowKind::Unilateral ? 0.5 + 0.5 * u(rng) : 0.2 * u(rng)) : 0;
        mu[r][l] = on ? static_cast<T>(0.6 + 0.4 * u(rng)) : 0;
      }
    }
  }

  BatchRows<T> rows(int count) {
    BatchRows<T> b;
    b.count = count;
    b.dofs = kDofs;
    b.kind = layout.kind;
    b.normal = layout.normal;
    b.J = J.data();
    b.nonzero_begin = nonzero_begin.data();
    b.nonzero_end = nonzero_end.data();
    b.zero_begin = zero_begin.data();
    b.zero_end = zero_end.data();
    b.MinvJT = z.data();
    b.target = target.data();
    b.cfm = cfm.data();
    b.mu = mu.data();
    b.active = active.data();
    b.inv_mass = inv_mass.data();
    b.lambda = lambda.data();
    return b;
  }
};

// lane 0 has every row, lane 1 lacks the second contact, lane 2 the first limit row, the others alternate
bool some_absent(int lane, int row) {
  if (lane == 1) return row >= 5;
  if (lane == 2) return row == 0;
  return lane > 2 && lane % 2 == 1 && row == 1;
}

// with a tolerance, each lane stops after the sweep where the scalar solve of its rows stops, converged where that
// converged
template <typename T>
void expect_lanes_match_the_scalar_solve(double friction_smoothing, double tolerance = 0, const Layout& layout = kPairs,
                                         bool (*absent)(int lane, int row) = some_absent) {
  std::mt19937 rng(11);
  Problem<T> p(rng, absent, layout);
  const int count = layout.count;
  PgsSettings settings;
  settings.iterations = tolerance > 0 ? 200 : 15;
  settings.cfm = 1e-6;
  settings.friction_smoothing = friction_smoothing;
  settings.tolerance = tolerance;
  std::vector<Lanes<T>> qd = p.qd, lambda = p.lambda;
  p.lambda = lambda;
  IntLanes<T> converged;
  const int sweeps = batch_pgs_solve(p.rows(count), settings, qd.data(), &converged);
  int most = 0, fewest = settings.iterations;

  for (int l = 0; l < kLanes<T>; ++l) {
    // the lane's rows as the solver's scalar path builds them: the rows it has, in order
    std::vector<PgsRow> rows;
    std::vector<Scalar> Jp, zp;
    std::vector<int> index(count, -1);
    for (int r = 0; r < count; ++r) {
      if (!p.active[r][l]) continue;
      PgsRow row;
      row.kind = layout.kind[r];
      row.dof_count[0] = kDofs;
      row.pool[0] = static_cast<int>(Jp.size());
      Scalar W = 0;
      for (int k = 0; k < kDofs; ++k) {
        Jp.push_back(p.J[r * kDofs + k][l]);
        zp.push_back(p.z[r * kDofs + k][l]);
        W += Jp.back() * zp.back();
      }
      row.cfm = p.cfm[r][l];
      row.inv_mass = 1 / (W + (settings.cfm + row.cfm));
      row.target = p.target[r][l];
      row.lambda = lambda[r][l];
      row.mu = p.mu[r][l];
      index[r] = static_cast<int>(rows.size());
      rows.push_back(row);
    }
    for (int r = 0; r < count; ++r)
      if (index[r] >= 0 && layout.normal[r] >= 0) rows[index[r]].normal = index[layout.normal[r]];
    std::vector<Scalar> v(kDofs);
    for (int k = 0; k < kDofs; ++k) v[k] = p.qd[k][l];
    std::vector<int> order(rows.size());
    for (size_t k = 0; k < rows.size(); ++k) {
      order[k] = static_cast<int>(k);
      apply_impulse(rows[k], zp, rows[k].lambda, v.data());
    }
    bool lane_converged = false;
    const int lane_sweeps =
        pgs_solve(rows, order.data(), static_cast<int>(rows.size()), Jp, zp, settings, v.data(), &lane_converged);
    // (with tolerance 0 a sweep's last bits decide it, and the two sum J qd in different orders)
    if (tolerance > 0) {
      EXPECT_EQ(converged[l] != 0, lane_converged) << "lane " << l;
    }
    most = std::max(most, lane_sweeps);
    fewest = std::min(fewest, lane_sweeps);

    double scale = 1, worst_qd = 0, worst_lambda = 0;
    for (const Scalar x : v) scale = std::max(scale, std::abs(x));
    for (int k = 0; k < kDofs; ++k) worst_qd = std::max(worst_qd, std::abs(qd[k][l] - v[k]) / scale);
    for (int r = 0; r < count; ++r) {
      const double expected = index[r] >= 0 ? rows[index[r]].lambda : 0;
      worst_lambda = std::max(worst_lambda, std::abs(p.lambda[r][l] - expected) / std::max(1.0, std::abs(expected)));
    }
    EXPECT_LT(worst_qd, 64 * kEps<T>) << "lane " << l;
    EXPECT_LT(worst_lambda, 64 * kEps<T>) << "lane " << l;
  }
  EXPECT_EQ(sweeps, most);
  if (tolerance > 0) {
    EXPECT_LT(sweeps, settings.iterations);  // stopped early
    EXPECT_LT(fewest, most);                 // the lanes at different sweeps: stopped lanes were masked
  }
}

// friction smoothing 1, 0 and 0.5 with every sweep; 1 and 0 with a tolerance
template <typename T>
void expect_lanes_match_the_scalar_solve_in_every_setting() {
  for (const auto& [smoothing, tolerance] :
       {std::pair{1.0, 0.0}, std::pair{0.0, 0.0}, std::pair{0.5, 0.0}, std::pair{1.0, 1e-3}, std::pair{0.0, 1e-3}}) {
    SCOPED_TRACE(testing::Message() << "friction_smoothing " << smoothing << ", tolerance " << tolerance);
    expect_lanes_match_the_scalar_solve<T>(smoothing, tolerance);
  }
}

TEST(BatchPgs, LanesMatchTheScalarSolveFloat64) { expect_lanes_match_the_scalar_solve_in_every_setting<double>(); }
TEST(BatchPgs, LanesMatchTheScalarSolveFloat32) { expect_lanes_match_the_scalar_solve_in_every_setting<float>(); }

// kCones' lanes: lane 1 lacks the condim 6 contact's rolling rows (a contact of condim 4 in a block laid out for 6),
// lane 2 also its torsional row (condim 3), lane 3 the second contact
bool some_cone_rows_absent(int lane, int row) {
  if (lane == 1) return row == 5 || row == 6;
  if (lane == 2) return row >= 4 && row <= 6;
  return lane == 3 && row >= 7 && row <= 9;
}

// FrictionCone rows: each lane as its scalar twin solves it (in which a lane's cone has only the rows it has), in
// every setting; with smoothing 1 every cone's impulses end within it, (l_i / mu_i) in the ball of radius the
// normal's impulse, and the random targets press some of them against it
template <typename T>
void expect_cones_match_the_scalar_solve_and_bound_their_rows() {
  for (const auto& [smoothing, tolerance] :
       {std::pair{1.0, 0.0}, std::pair{0.0, 0.0}, std::pair{0.5, 0.0}, std::pair{1.0, 1e-3}}) {
    SCOPED_TRACE(testing::Message() << "friction_smoothing " << smoothing << ", tolerance " << tolerance);
    expect_lanes_match_the_scalar_solve<T>(smoothing, tolerance, kCones, some_cone_rows_absent);
  }
  std::mt19937 rng(11);
  Problem<T> p(rng, some_cone_rows_absent, kCones);
  std::vector<Lanes<T>> qd = p.qd;
  PgsSettings settings;
  settings.iterations = 15;
  batch_pgs_solve(p.rows(kCones.count), settings, qd.data());
  int pressed = 0;
  for (int l = 0; l < kLanes<T>; ++l) {
    for (const auto& [normal, first, last] : {std::tuple{1, 2, 6}, std::tuple{7, 8, 9}}) {
      double sum = 0;
      for (int r = first; r <= last; ++r)
        if (p.active[r][l]) sum += std::pow(double(p.lambda[r][l]) / p.mu[r][l], 2);
      const double radius = p.lambda[normal][l];
      EXPECT_LE(std::sqrt(sum), radius * (1 + 8 * kEps<T>)) << "lane " << l << ", the cone of row " << normal;
      pressed += radius > 0 && std::sqrt(sum) > radius * (1 - 8 * kEps<T>);
    }
  }
  EXPECT_GT(pressed, 0);
}

TEST(BatchPgs, ConesMatchTheScalarSolveAndBoundTheirRowsFloat64) {
  expect_cones_match_the_scalar_solve_and_bound_their_rows<double>();
}
TEST(BatchPgs, ConesMatchTheScalarSolveAndBoundTheirRowsFloat32) {
  expect_cones_match_the_scalar_solve_and_bound_their_rows<float>();
}

template <typename T>
void expect_absent_rows_change_no_bit(double tolerance) {
  // lane 1 lacks the last contact: solved beside lanes that have it, its velocity and impulses are
  // bit for bit those of a block without that contact (with a tolerance, whenever the others stop)
  std::mt19937 rng(5);
  Problem<T> with(rng, some_absent);
  Problem<T> without = with;
  PgsSettings settings;
  settings.iterations = tolerance > 0 ? 200 : 20;
  settings.tolerance = tolerance;
  std::vector<Lanes<T>> a = with.qd, b = without.qd;
  batch_pgs_solve(with.rows(kRows), settings, a.data());
  batch_pgs_solve(without.rows(5), settings, b.data());
  for (int k = 0; k < kDofs; ++k) EXPECT_EQ(std::memcmp(&a[k][1], &b[k][1], sizeof(T)), 0) << "dof " << k;
  for (int r = 0; r < kRows; ++r) EXPECT_EQ(std::memcmp(&with.lambda[r][1], &without.lambda[r][1], sizeof(T)), 0);
}

// with tolerance 0 the sweeps stop after the first that changes no impulse in a lane (a fixed point,
// which PGS reaches where rows separate: their impulses clamp to zero and stay there; rows that push
// mostly keep changing in the last bit). That sweep changed nothing, so stopping before it by the
// iteration cap gives the same bits. Here every row separates (targets far below any velocity) from
// warm starts: the first sweep clamps every impulse to zero, the second changes nothing
template <typename T>
void expect_a_fixed_point_ends_the_sweeps() {
  std::mt19937 rng(3);
  Problem<T> start(rng, some_absent);
  for (Lanes<T>& target : start.target) target = Lanes<T>{} - 100;
  PgsSettings settings;
  settings.cfm = 1e-6;
  Problem<T> a = start, b = start;
  std::vector<Lanes<T>> qd_a = start.qd, qd_b = start.qd;
  IntLanes<T> converged_a, converged_b;
  EXPECT_EQ(batch_pgs_solve(a.rows(kRows), settings, qd_a.data(), &converged_a), 2);
  settings.iterations = 1;
  batch_pgs_solve(b.rows(kRows), settings, qd_b.data(), &converged_b);
  EXPECT_FALSE(any_lane<T>(~converged_a));  // the second sweep moved nothing
  EXPECT_FALSE(any_lane<T>(converged_b));   // the one sweep allowed moved the rows: ran out
  EXPECT_EQ(std::memcmp(qd_a.data(), qd_b.data(), kDofs * sizeof(Lanes<T>)), 0);
  EXPECT_EQ(std::memcmp(a.lambda.data(), b.lambda.data(), kRows * sizeof(Lanes<T>)), 0);
  EXPECT_NE(std::memcmp(qd_a.data(), start.qd.data(), kDofs * sizeof(Lanes<T>)), 0);  // the first sweep did act
}
TEST(BatchPgs, AFixedPointEndsTheSweepsFloat64) { expect_a_fixed_point_ends_the_sweeps<double>(); }
TEST(BatchPgs, AFixedPointEndsTheSweepsFloat32) { expect_a_fixed_point_ends_the_sweeps<float>(); }

// the scalar twin likewise: two coupled limit-like rows over three dofs, separating from warm starts
TEST(Pgs, AFixedPointEndsTheSweeps) {
  const std::vector<Scalar> J = {1, 0.5, 0, 0, 1, -0.3}, z = {0.8, 0.2, -0.1, 0.1, 0.7, -0.4};
  std::vector<PgsRow> start(2);
  for (int r = 0; r < 2; ++r) {
    start[r].dof_count[0] = 3;
    start[r].pool[0] = 3 * r;
    start[r].target = -100;
    start[r].lambda = 0.5;
    Scalar W = 0;
    for (int k = 0; k < 3; ++k) W += J[3 * r + k] * z[3 * r + k];
    start[r].inv_mass = 1 / W;
  }
  const int order[] = {0, 1};
  PgsSettings settings;
  std::vector<PgsRow> a = start, b = start;
  const std::vector<Scalar> qd = {0.1, -0.2, 0.3};
  std::vector<Scalar> qd_a = qd, qd_b = qd;
  bool converged_a = false, converged_b = true;
  EXPECT_EQ(pgs_solve(a, order, 2, J, z, settings, qd_a.data(), &converged_a), 2);
  settings.iterations = 1;
  pgs_solve(b, order, 2, J, z, settings, qd_b.data(), &converged_b);
  EXPECT_TRUE(converged_a);
  EXPECT_FALSE(converged_b);
  EXPECT_EQ(std::memcmp(qd_a.data(), qd_b.data(), 3 * sizeof(Scalar)), 0);
  for (int r = 0; r < 2; ++r) EXPECT_EQ(a[r].lambda, 0);
  EXPECT_NE(qd_a, qd);
}

// the lanes' contact frames (contact_frame on lanes) against contact_tangents in double: random unit normals and the
// axes, signed zeros included; each frame orthonormal with t1 x t2 = n
template <typename T>
void expect_lane_frames_match_contact_tangents() {
  using V = Lanes<T>;
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  std::vector<Vec3> normals = {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0, 1, -0.0)};
  while (normals.size() < 64 * kLanes<T>) normals.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
  double worst = 0;
  for (size_t first = 0; first < normals.size(); first += kLanes<T>) {
    V n[3], d[9];
    for (int l = 0; l < kLanes<T>; ++l)
      for (int m = 0; m < 3; ++m) n[m][l] = static_cast<T>(normals[first + l][m]);
    contact_frame<V>(n, d);
    for (int l = 0; l < kLanes<T>; ++l) {
      const Vec3 normal(n[0][l], n[1][l], n[2][l]);
      Vec3 t1, t2;
      contact_tangents(normal, &t1, &t2);
      const Vec3 ref[3] = {normal, t1, t2};
      Vec3 lane[3];
      for (int e = 0; e < 3; ++e) {
        lane[e] = Vec3(d[3 * e][l], d[3 * e + 1][l], d[3 * e + 2][l]);
        worst = std::max(worst, (lane[e] - ref[e]).cwiseAbs().maxCoeff() / kEps<T>);
      }
      EXPECT_NEAR(lane[1].dot(lane[0]), 0, 8 * kEps<T>);
      EXPECT_NEAR(lane[2].dot(lane[0]), 0, 8 * kEps<T>);
      EXPECT_NEAR(lane[1].dot(lane[2]), 0, 8 * kEps<T>);
      EXPECT_NEAR((lane[1].cross(lane[2]) - lane[0]).norm(), 0, 8 * kEps<T>);
    }
  }
  EXPECT_LT(worst, 8);
}

TEST(BatchPgs, LaneFramesMatchContactTangentsFloat64) { expect_lane_frames_match_contact_tangents<double>(); }
TEST(BatchPgs, LaneFramesMatchContactTangentsFloat32) { expect_lane_frames_match_contact_tangents<float>(); }

TEST(BatchPgs, AbsentRowsChangeNoBitOfTheirLane) {
  for (const double tolerance : {0.0, 1e-3}) {
    expect_absent_rows_change_no_bit<double>(tolerance);
    expect_absent_rows_change_no_bit<float>(tolerance);
  }
}

TEST(BatchPgs, NonFiniteRowsSpreadNothing) {
  // lane 0's normal row (as max(0, NaN) in the scalar twin: no impulse) and friction pair (keeps its
  // warm start) turn NaN; its velocity stays finite, and the other lanes solve as without it
  std::mt19937 rng(3);
  Problem<double> p(rng, [](int, int) { return false; });
  Problem<double> clean = p;
  p.target[5][0] = p.target[3][0] = std::numeric_limits<double>::quiet_NaN();
  PgsSettings settings;
  std::vector<Lanes<double>> a = p.qd, b = clean.qd;
  const double warm3 = p.lambda[3][0], warm4 = p.lambda[4][0];
  batch_pgs_solve(p.rows(kRows), settings, a.data());
  batch_pgs_solve(clean.rows(kRows), settings, b.data());
  EXPECT_EQ(p.lambda[5][0], 0);
  EXPECT_EQ(p.lambda[3][0], warm3);
  EXPECT_EQ(p.lambda[4][0], warm4);
  for (int k = 0; k < kDofs; ++k) {
    EXPECT_TRUE(std::isfinite(a[k][0])) << "dof " << k;
    for (int l = 1; l < kLanes<double>; ++l) EXPECT_EQ(a[k][l], b[k][l]);
  }
}

// Bounded rows (a joint's dry friction): each lane's impulses within +-bound, as the scalar twin clamps them
template <typename T>
void expect_bounded_rows_match_the_scalar_solve() {
  using V = Lanes<T>;
  constexpr int kBounded = 3;
  const RowKind kinds[kBounded] = {RowKind::Bounded, RowKind::Bounded, RowKind::Bounded};
  const int normals[kBounded] = {-1, -1, -1};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<V> J(kBounded * kDofs), z(kBounded * kDofs), target(kBounded), cfm(kBounded), mu(kBounded),
      bound(kBounded), inv_mass(kBounded), lambda(kBounded), qd(kDofs);
  std::vector<IntLanes<T>> active(kBounded, ~IntLanes<T>{});
  std::vector<int> begin(kBounded, 0), end(kBounded, kDofs), none(kBounded, 0);
  std::vector<Eigen::LLT<Eigen::MatrixXd>> llt;
  for (int l = 0; l < kLanes<T>; ++l) {
    Eigen::MatrixXd A = Eigen::MatrixXd::NullaryExpr(kDofs, kDofs, [&] { return u(rng); });
    llt.emplace_back(A * A.transpose() + Eigen::MatrixXd::Identity(kDofs, kDofs));
    for (int k = 0; k < kDofs; ++k) qd[k][l] = static_cast<T>(3 * u(rng));
    for (int r = 0; r < kBounded; ++r) {
      Eigen::VectorXd j = Eigen::VectorXd::Zero(kDofs);
      j[2 * r] = 1;  // J = e_k, a dof's row
      const Eigen::VectorXd x = llt.back().solve(j);
      for (int k = 0; k < kDofs; ++k)
        J[r * kDofs + k][l] = static_cast<T>(j[k]), z[r * kDofs + k][l] = static_cast<T>(x[k]);
      bound[r][l] = static_cast<T>(0.05 + 0.1 * (1 + u(rng)));
      lambda[r][l] = static_cast<T>(0.05 * u(rng));
    }
  }
  PgsSettings settings;
  settings.iterations = 12;
  settings.cfm = 1e-6;
  std::vector<V> lanes_qd = qd, lanes_lambda = lambda;
  BatchRows<T> rows;
  rows.count = kBounded;
  rows.dofs = kDofs;
  rows.kind = kinds;
  rows.normal = normals;
  rows.J = J.data();
  rows.nonzero_begin = begin.data();
  rows.nonzero_end = end.data();
  rows.zero_begin = rows.zero_end = none.data();
  rows.MinvJT = z.data();
  rows.target = target.data();
  rows.cfm = cfm.data();
  rows.mu = mu.data();
  rows.bound = bound.data();
  rows.active = active.data();
  rows.inv_mass = inv_mass.data();
  rows.lambda = lanes_lambda.data();
  batch_pgs_solve(rows, settings, lanes_qd.data());
  for (int l = 0; l < kLanes<T>; ++l) {
    std::vector<PgsRow> scalar(kBounded);
    std::vector<Scalar> Jp, zp, v(kDofs);
    std::vector<int> order(kBounded);
    for (int k = 0; k < kDofs; ++k) v[k] = qd[k][l];
    for (int r = 0; r < kBounded; ++r) {
      scalar[r].kind = RowKind::Bounded;
      scalar[r].dof_count[0] = kDofs;
      scalar[r].pool[0] = static_cast<int>(Jp.size());
      Scalar W = 0;
      for (int k = 0; k < kDofs; ++k)
        Jp.push_back(J[r * kDofs + k][l]), zp.push_back(z[r * kDofs + k][l]), W += Jp.back() * zp.back();
      scalar[r].inv_mass = 1 / (W + settings.cfm);
      scalar[r].bound = bound[r][l];
      scalar[r].lambda = lambda[r][l];
      order[r] = r;
    }
    for (int r = 0; r < kBounded; ++r) apply_impulse(scalar[r], zp, scalar[r].lambda, v.data());
    pgs_solve(scalar, order.data(), kBounded, Jp, zp, settings, v.data());
    for (int r = 0; r < kBounded; ++r) {
      EXPECT_LE(std::abs(lanes_lambda[r][l]), bound[r][l]) << "lane " << l << " row " << r;
      EXPECT_NEAR(lanes_lambda[r][l], scalar[r].lambda, 64 * kEps<T>) << "lane " << l << " row " << r;
    }
    for (int k = 0; k < kDofs; ++k) EXPECT_NEAR(lanes_qd[k][l], v[k], 64 * kEps<T> * 4) << "lane " << l;
  }
}

TEST(BatchPgs, BoundedRowsMatchTheScalarSolveFloat64) { expect_bounded_rows_match_the_scalar_solve<double>(); }
TEST(BatchPgs, BoundedRowsMatchTheScalarSolveFloat32) { expect_bounded_rows_match_the_scalar_solve<float>(); }

}  // namespace
}  // namespace novaphy
