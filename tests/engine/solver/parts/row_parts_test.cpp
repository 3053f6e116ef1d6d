// Each row part (engine/solver/parts/rows.h) on its own, with a plain number (one world) and with a SIMD block's
// lanes: each lane's numbers are what the plain number gives for that lane's inputs (lanes do not leak into each
// other), and the plain numbers are what the part's physics says (analytic cases).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "engine/model/builder.h"
#include "engine/solver/parts/rows.h"
#include "kernels/lanes.h"

namespace novaphy {
namespace {

constexpr Scalar kNaN = std::numeric_limits<Scalar>::quiet_NaN();

template <typename T>
class RowParts : public ::testing::Test {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(RowParts, Precisions);

// lane l's inputs of a test: a value per lane from f(l)
template <typename T, typename F>
Lanes<T> lanes_of(F f) {
  Lanes<T> x{};
  for (int l = 0; l < kLanes<T>; ++l) x[l] = static_cast<T>(f(l));
  return x;
}

// x's lane l is the plain number y (to a few ulps: the compiler may fuse a multiply and add in one and not the other)
template <typename T>
void expect_lane(const Lanes<T>& x, int l, T y, const char* what) {
  const T tolerance = 8 * std::numeric_limits<T>::epsilon() * std::max<T>(1, std::abs(y));
  EXPECT_NEAR(x[l], y, tolerance) << what << " lane " << l;
}

TYPED_TEST(RowParts, LimitRowIsOnWhereTheCoordinateWouldCrossAndPushesOutBeyondTheSlop) {
  using T = TypeParam;
  SolverFeatherstoneSettings p;
  p.erp = 0.2;
  p.linear_slop = 0.001;
  const T dt = T(0.01);
  const T inf = std::numeric_limits<T>::infinity();
  // plain: a side's gap is >= 0 inside the range; its row is on where the coordinate would cross the (finite) limit
  // within the step
  EXPECT_EQ(LimitRow::gap<T>(T(0.25), T(0.2), 0), T(0.25) - T(0.2));
  EXPECT_EQ(LimitRow::gap<T>(T(0.25), T(0.3), 1), -(T(0.25) - T(0.3)));
  EXPECT_FALSE(LimitRow::on<T>(T(0), T(0.02), T(-1), 0, dt, false));
  EXPECT_TRUE(LimitRow::on<T>(T(0), T(0.005), T(-1), 0, dt, false));
  EXPECT_TRUE(LimitRow::on<T>(T(1), T(0.005), T(1), 1, dt, false));  // the upper side, approached from below
  EXPECT_FALSE(LimitRow::on<T>(T(1), T(0.005), T(-1), 1, dt, false));
  EXPECT_FALSE(LimitRow::on<T>(inf, -inf, T(-1), 0, dt, false));
  // a soft row (MuJoCo's rule): on where the coordinate is past the limit, moving in or out, not before
  EXPECT_TRUE(LimitRow::on<T>(T(0), T(-0.001), T(1), 0, dt, true));
  EXPECT_FALSE(LimitRow::on<T>(T(0), T(0.005), T(-1), 0, dt, true));
  EXPECT_FALSE(LimitRow::on<T>(inf, -inf, T(-1), 0, dt, true));
  // closing the gap in one step; beyond it, erp of the depth past the slop per step
  EXPECT_NEAR(LimitRow::target<T>(T(0.005), p, dt), T(-0.5), 1e-5);
  EXPECT_NEAR(LimitRow::target<T>(T(-0.011), p, dt), T(0.2 * 0.01 / 0.01), 1e-5);
  EXPECT_EQ(LimitRow::target<T>(T(-0.0005), p, dt), T(0));  // within the slop
  EXPECT_EQ(LimitRow::kKind, RowKind::Unilateral);
  // lanes: lane l's gap and velocity against a lower limit (none in the last lane)
  auto gap = [](int l) { return 0.0037 * (l % 5) - 0.01; };
  auto velocity = [](int l) { return 0.55 - 0.35 * (l % 3); };  // (no lane at gap + dt v = 0)
  auto limit = [](int l) { return l == kLanes<T> - 1 ? std::numeric_limits<Scalar>::infinity() : 0.0; };
  const Lanes<T> g = lanes_of<T>(gap), v = lanes_of<T>(velocity), dts = splat<Lanes<T>>(dt);
  IntLanes<T> soft{};  // (soft in every third lane)
  for (int l = 0; l < kLanes<T>; ++l) soft[l] = l % 3 == 1 ? -1 : 0;
  const IntLanes<T> on = LimitRow::on(lanes_of<T>(limit), g, v, 0, dts, soft);
  const Lanes<T> target = LimitRow::target(g, p, dts);
  for (int l = 0; l < kLanes<T>; ++l) {
    EXPECT_EQ(on[l] != 0, LimitRow::on<T>(T(limit(l)), T(gap(l)), T(velocity(l)), 0, dt, l % 3 == 1)) << "lane " << l;
    expect_lane<T>(target, l, LimitRow::target<T>(T(gap(l)), p, dt), "target");
  }
}

// MuJoCo's soft row over one step for a one-dof row of inverse mass A with no other force: the impulse the row's
// cfm and target give, p = (target - v) / (A + cfm), is MuJoCo's f dt with f = aref / (A + R), aref = -B v - K imp pos
TEST(RowParts, SoftRowsAreMujocosSoftConstraintOverOneStep) {
  const Scalar solref[2] = {0.02, 1}, solimp[5] = {0.9, 0.95, 0.001, 0.5, 2}, dt = 0.002, weight = 4, A = 5;
  // K and B: 1 / (dmax^2 tc^2 dampratio^2) and 2 / (dmax tc), the time constant at least 2 dt (refsafe)
  const SoftReference k = soft_reference(solref, solimp, dt);
  EXPECT_NEAR(k.stiffness, 1 / (0.95 * 0.95 * 0.02 * 0.02), 1e-9);
  EXPECT_NEAR(k.damping, 2 / (0.95 * 0.02), 1e-12);
  const Scalar fast[2] = {0.001, 1};
  EXPECT_NEAR(soft_reference(fast, solimp, dt).damping, 2 / (0.95 * 2 * dt), 1e-9);
  const Scalar direct[2] = {-1000, -20};
  EXPECT_NEAR(soft_reference(direct, solimp, dt).stiffness, 1000 / (0.95 * 0.95), 1e-9);
  EXPECT_NEAR(soft_reference(direct, solimp, dt).damping, 20 / 0.95, 1e-12);
  // a limit 0.26 past (imp at dmax), moving out at 0.3
  Softness s = softness_of(solref, solimp, weight);
  const Scalar gap = -0.26, v = 0.3;
  const SoftRow row = LimitRow::soft(gap, v, s, dt);
  const Scalar R = (1 - 0.95) / 0.95 * weight, aref = -k.damping * v - k.stiffness * 0.95 * gap;
  EXPECT_NEAR(row.cfm, R, 1e-15);
  EXPECT_NEAR((row.target - v) / (A + row.cfm), aref / (A + R) * dt, 1e-12);
  // dry friction: no stiffness, the impedance at 0 (dmin)
  const SoftRow friction = FrictionLossRow::soft(v, s, dt);
  EXPECT_NEAR(friction.cfm, (1 - 0.9) / 0.9 * weight, 1e-15);
  EXPECT_NEAR(friction.target, v - dt * k.damping * v, 1e-15);
  // an equality: its impedance at its whole error, its stiffness on the row's part of it
  s.solimp[2] = 0.1;  // (a width the error falls within)
  const SoftRow equality = EqualityRow::soft(0.03, 0.05, v, s, dt);
  const Scalar imp = impedance(s.solimp, 0.05);
  EXPECT_GT(imp, 0.9);
  EXPECT_LT(imp, 0.95);
  EXPECT_NEAR(equality.cfm, (1 - imp) / imp * weight, 1e-15);
  EXPECT_NEAR(equality.target, v - dt * (k.damping * v + k.stiffness * imp * 0.03), 1e-12);
  EXPECT_FALSE(is_soft(std::array<Scalar, 2>{0, 0}.data()));
  EXPECT_TRUE(is_soft(direct));
}

TYPED_TEST(RowParts, FrictionLossRowIsBoundedByTheLossOverTheStep) {
  using T = TypeParam;
  const T dt = T(0.002);
  EXPECT_FALSE(FrictionLossRow::on<T>(T(0)));
  EXPECT_TRUE(FrictionLossRow::on<T>(T(0.3)));
  EXPECT_NEAR(FrictionLossRow::bound<T>(T(0.3), dt), T(0.0006), 1e-9);
  EXPECT_EQ(FrictionLossRow::kKind, RowKind::Bounded);
  auto loss = [](int l) { return l % 2 ? 0.1 * l : 0.0; };
  const Lanes<T> x = lanes_of<T>(loss);
  const IntLanes<T> on = FrictionLossRow::on(x);
  const Lanes<T> bound = FrictionLossRow::bound(x, splat<Lanes<T>>(dt));
  for (int l = 0; l < kLanes<T>; ++l) {
    EXPECT_EQ(on[l] != 0, loss(l) > 0) << "lane " << l;
    expect_lane<T>(bound, l, FrictionLossRow::bound<T>(T(loss(l)), dt), "bound");
  }
}

TYPED_TEST(RowParts, KeptImpulsesStartTheirWorldsShareAndKeepOnlyFiniteImpulsesOfRowsThatWereOn) {
  using T = TypeParam;
  SolverFeatherstoneSettings p;
  p.warmstarting_factor = 0.85;
  EXPECT_EQ(warm_share<T>(true, p), T(1));
  EXPECT_EQ(warm_share<T>(false, p), T(0.85));
  IntLanes<T> converged{};  // a world's share by its own sweeps
  for (int l = 0; l < kLanes<T>; ++l) converged[l] = l % 2 ? -1 : 0;
  const Lanes<T> share = warm_share<Lanes<T>>(converged, p);
  for (int l = 0; l < kLanes<T>; ++l) EXPECT_EQ(share[l], l % 2 ? T(1) : T(0.85)) << "lane " << l;
  p.use_warmstarting = false;
  EXPECT_EQ(warm_share<T>(true, p), T(0));
  EXPECT_EQ(LimitRow::warm<T>(T(2), T(0.5)), T(1));
  EXPECT_EQ(EqualityRow::keep<T>(T(3), true), T(3));
  EXPECT_EQ(EqualityRow::keep<T>(T(3), false), T(0));
  EXPECT_EQ(EqualityRow::keep<T>(static_cast<T>(kNaN), true), T(0));
  // lanes: a NaN (the last lane) or an off row (the first) in one lane does not touch the others
  constexpr int kNaNLane = kLanes<T> - 1, kOffLane = 0;
  const Lanes<T> lambda = lanes_of<T>([](int l) { return l == kNaNLane ? kNaN : 0.25 * (l + 1); });
  IntLanes<T> on{};
  for (int l = 0; l < kLanes<T>; ++l) on[l] = l == kOffLane ? 0 : -1;
  const Lanes<T> kept = FrictionLossRow::keep(lambda, on);
  for (int l = 0; l < kLanes<T>; ++l)
    EXPECT_EQ(kept[l], l == kNaNLane || l == kOffLane ? T(0) : T(0.25 * (l + 1))) << "lane " << l;
}

TEST(RowParts, EqualityRowsDriveTheirErrorsToZero) {
  SolverFeatherstoneSettings p;
  p.erp = 0.2;
  EXPECT_NEAR(EqualityRow::target<Scalar>(0.01, p, 0.01), -0.2, 1e-15);
  EXPECT_EQ(EqualityRow::bound(), std::numeric_limits<Scalar>::infinity());
  EXPECT_EQ(EqualityRow::kKind, RowKind::Bounded);
  EXPECT_EQ(EqualityRow::count(EqualityType::Weld), 6);
  EXPECT_EQ(EqualityRow::count(EqualityType::Connect), 3);
  EXPECT_EQ(EqualityRow::count(EqualityType::JointCoupling), 1);
  // a coupling's slope is its polynomial's derivative
  const JointCoupling coupling{{0.1, 0.5, -0.3, 0.2, 0.05}, 0.2, -0.1};
  Scalar slope = 0, ignored = 0;
  const Scalar q2 = 0.4, h = 1e-6;
  coupling.error(1, q2, &slope);
  const Scalar numeric = -(coupling.error(1, q2 + h, &ignored) - coupling.error(1, q2 - h, &ignored)) / (2 * h);
  EXPECT_NEAR(slope, numeric, 1e-8);
  EXPECT_NEAR(coupling.error(0.2 + 0.1, -0.1, &ignored), 0, 1e-15);  // q1 - q1_ref = poly(0) = a0
  // a weld whose body 2 turned by 0.3 rad about z from its held orientation; its anchors 0.1 apart along x
  const BodyEquality weld{Vec3::Zero(), Vec3::Zero(), Quat::Identity()};
  Transform X1, X2;
  X2.p = Vec3(0.1, 0, 0);
  X2.q = Quat(Eigen::AngleAxis<Scalar>(0.3, Vec3::UnitZ()));
  Vec3 mid, gap, turn;
  weld.errors(X1, X2, &mid, &gap, &turn);
  EXPECT_TRUE(gap.isApprox(Vec3(0.1, 0, 0)));
  EXPECT_TRUE(mid.isApprox(Vec3(0.05, 0, 0)));
  EXPECT_TRUE(turn.isApprox(Vec3(0, 0, 0.3)));
}

// the records read a model's equality_data as the builder wrote it
TEST(RowParts, EqualityRecordsReadTheModelsData) {
  ModelBuilder builder(Vec3::Zero());
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.dof.q0 = 0.4;
  const int a = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)));
  const int j1 = builder.add_joint_revolute(-1, a, options);
  options.dof.q0 = -0.7;
  const int b = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)));
  const int j2 = builder.add_joint_revolute(a, b, options);
  const Vec3 anchor1(0.1, 0.2, 0.3), anchor2(0.4, 0.5, 0.6), weld_anchor(0.1, -0.2, 0.05);
  builder.add_connect(a, b, anchor1, "", anchor2);
  Transform relative;
  relative.p = Vec3(0, 0, 1);
  relative.q = Quat(Eigen::AngleAxis<Scalar>(0.3, Vec3(1, 2, 3).normalized()));
  builder.add_weld(a, b, "", weld_anchor, relative);
  builder.add_joint_coupling(j1, j2, {0.1, 0.5, -0.3, 0.2, 0.05});
  const Model model = builder.finalize();
  const BodyEquality connect = BodyEquality::of(model, 0), weld = BodyEquality::of(model, 1);
  EXPECT_EQ(connect.anchor1, anchor1);
  EXPECT_EQ(connect.anchor2, anchor2);
  EXPECT_EQ(weld.anchor2, weld_anchor);
  EXPECT_TRUE(weld.anchor1.isApprox(relative.apply(weld_anchor)));
  EXPECT_TRUE(weld.relative.coeffs().isApprox(relative.q.coeffs()));  // (w read from its place, not x's)
  const JointCoupling coupling = JointCoupling::of(model, 2);
  const Scalar poly[5] = {0.1, 0.5, -0.3, 0.2, 0.05};
  for (int k = 0; k < 5; ++k) EXPECT_EQ(coupling.poly[k], poly[k]);
  EXPECT_EQ(coupling.q1_ref, 0.4);
  EXPECT_EQ(coupling.q2_ref, -0.7);
  // a connect held at bodies turned and moved: the gap between its anchors in the world, acting at their middle
  Transform X1, X2;
  X1.q = Quat(Eigen::AngleAxis<Scalar>(0.5, Vec3::UnitZ()));
  X2.p = Vec3(0.3, 0, 0);
  Vec3 mid, gap;
  connect.errors(X1, X2, &mid, &gap, nullptr);
  const Vec3 p1 = X1.q * anchor1, p2 = X2.p + anchor2;
  EXPECT_TRUE(gap.isApprox(p2 - p1));
  EXPECT_TRUE(mid.isApprox((p1 + p2) / 2));
}

constexpr Scalar kImpratio = 2;

// a contact's input of lane l: soft in the even lanes, rigid in the odd ones, at depths and speeds of its own
ContactInput<Scalar> contact_of(int l) {
  ContactInput<Scalar> in;
  in.depth = 0.002 * (l % 4) - 0.001;
  in.mu = 0.5 + 0.1 * l;
  in.restitution = l % 2 ? 0.5 : 0;
  for (int m = 0; m < 3; ++m) {
    in.impulse[m] = 0.01 * (m + 1) * (l % 2 ? 1 : -1);
    in.spin[m] = 0.001 * (m + 1) * (l % 4 ? 1 : -1);
  }
  in.condim = l % 3 == 2 ? 6 : 3;
  in.torsion = 0.02;
  in.rolling = l % 2 ? 0.001 : 0;
  if (l % 2 == 0) {
    ContactPair pair;
    pair.soft = true;
    pair.stiffness = 2500;
    pair.damping = 100;
    pair.solimp[0] = 0.9, pair.solimp[1] = 0.95, pair.solimp[2] = 0.001, pair.solimp[3] = 0.5, pair.solimp[4] = 2;
    in.softness = contact_softness(pair, 0.5, 0, kImpratio, in.depth);
  }
  return in;
}

template <typename T>
ContactInput<T> plain(const ContactInput<Scalar>& in) {
  ContactInput<T> x;
  x.depth = T(in.depth), x.mu = T(in.mu), x.restitution = T(in.restitution);
  for (int m = 0; m < 3; ++m) x.impulse[m] = T(in.impulse[m]), x.spin[m] = T(in.spin[m]);
  x.softness = {in.softness.soft,       T(in.softness.cfm_normal), T(in.softness.cfm_friction),
                T(in.softness.damping), T(in.softness.spring),     T(in.softness.active_margin)};
  x.condim = T(in.condim), x.torsion = T(in.torsion), x.rolling = T(in.rolling);
  return x;
}

TYPED_TEST(RowParts, ContactRowsOfEachLaneAreThoseOfItsContactAlone) {
  using T = TypeParam;
  using V = Lanes<T>;
  SolverFeatherstoneSettings p;
  const T dt = T(0.002);
  ContactInput<V> in;
  for (int l = 0; l < kLanes<T>; ++l) ContactRows::set_lane(in, l, contact_of(l));
  T n[3] = {T(0.6), T(0), T(0.8)}, d[9];
  contact_frame(n, d);
  V nv[3], dv[9];
  for (int m = 0; m < 3; ++m) nv[m] = splat<V>(n[m]);
  contact_frame(nv, dv);
  V v[6], target[6], cfm[6], mu[6], warm[6];
  // (the normal's velocity: from 0.1 down to fast approaches, beyond the restitution threshold, in the later lanes)
  for (int e = 0; e < 6; ++e) v[e] = lanes_of<T>([e](int l) { return 0.1 * (e + 1) - (e == 0 ? 0.11 : 0.05) * l; });
  ContactRows::targets(in, v, 6, p, splat<V>(dt), target, cfm, mu);
  ContactRows::warm(in, dv, ContactRows::warm_share<V>(p), warm);
  for (int l = 0; l < kLanes<T>; ++l) {
    const ContactInput<T> one = plain<T>(contact_of(l));
    T vl[6], target_l[6], cfm_l[6], mu_l[6], warm_l[6];
    for (int e = 0; e < 6; ++e) vl[e] = v[e][l];
    ContactRows::targets(one, vl, 6, p, dt, target_l, cfm_l, mu_l);
    ContactRows::warm(one, d, ContactRows::warm_share<T>(p), warm_l);
    for (int e = 0; e < 6; ++e) {
      expect_lane<T>(target[e], l, target_l[e], "target");
      expect_lane<T>(cfm[e], l, cfm_l[e], "cfm");
      expect_lane<T>(mu[e], l, mu_l[e], "mu");
      expect_lane<T>(warm[e], l, warm_l[e], "warm");
    }
    // the plain numbers' physics: a rigid contact has no cfm and its friction rows no target, and bounces back at
    // restitution times its approach where it closes faster than the threshold; a soft one's friction rows are
    // softer than its normal by impratio, and it has none while inactive; the normal never starts pulling
    if (!one.softness.soft) {
      EXPECT_EQ(cfm_l[0], T(0)) << "lane " << l;
      EXPECT_EQ(target_l[1], T(0)) << "lane " << l;
      if (vl[0] < -p.restitution_threshold && one.depth - vl[0] * dt >= 0) {
        EXPECT_GE(target_l[0], T(0.999) * one.restitution * -vl[0]) << "lane " << l;
      }
    } else {
      if (one.depth > 0) {  // (active: nearer than its margin, 0)
        EXPECT_GT(cfm_l[0], T(0)) << "lane " << l;
      } else {
        EXPECT_EQ(cfm_l[0], T(0)) << "lane " << l;
      }
      EXPECT_NEAR(cfm_l[1], cfm_l[0] / T(kImpratio), 4 * std::numeric_limits<T>::epsilon() * cfm_l[0]) << l;
    }
    EXPECT_GE(warm_l[0], T(0)) << "lane " << l;
    EXPECT_EQ(mu_l[0], T(0));
    EXPECT_EQ(mu_l[1], one.mu);
    EXPECT_EQ(mu_l[3], one.torsion);
    EXPECT_EQ(mu_l[5], one.rolling);
  }
}

TYPED_TEST(RowParts, AContactsRowsBeyondItsDimsAreLeftAloneAndItsConditionSaysWhichItHas) {
  using T = TypeParam;
  SolverFeatherstoneSettings p;
  const ContactInput<T> in = plain<T>(contact_of(0));
  const T v[6] = {T(-0.1), T(0.2), T(0.3), T(0.4), T(0.5), T(0.6)};
  T all[3][6], target[6], cfm[6], mu[6];
  ContactRows::targets(in, v, 6, p, T(0.002), all[0], all[1], all[2]);
  for (const int dims : {3, 4}) {
    std::fill(target, target + 6, T(7));
    std::fill(cfm, cfm + 6, T(7));
    std::fill(mu, mu + 6, T(7));
    ContactRows::targets(in, v, dims, p, T(0.002), target, cfm, mu);
    for (int e = 0; e < 6; ++e) {
      EXPECT_EQ(target[e], e < dims ? all[0][e] : T(7)) << dims << " rows, row " << e;
      EXPECT_EQ(cfm[e], e < dims ? all[1][e] : T(7)) << dims << " rows, row " << e;
      EXPECT_EQ(mu[e], e < dims ? all[2][e] : T(7)) << dims << " rows, row " << e;
    }
  }
  for (const int condim : {1, 3, 4, 5, 6}) {
    for (int e = 0; e < 6; ++e)
      EXPECT_EQ(ContactRows::has<T>(e, T(condim)), e < 3 || (e == 3 && condim >= 4) || condim == 6)
          << "condim " << condim << ", row " << e;
    EXPECT_EQ(ContactRows::count(condim), condim == 6 ? 6 : condim >= 4 ? 4 : 3) << "condim " << condim;
  }
  // without warm starting a contact starts from nothing
  p.use_warmstarting = false;
  T d[9], warm[6];
  const T n[3] = {T(0), T(0), T(1)};
  contact_frame(n, d);
  ContactRows::warm(in, d, ContactRows::warm_share<T>(p), warm);
  for (int e = 0; e < 6; ++e) EXPECT_EQ(warm[e], T(0)) << "row " << e;
}

TYPED_TEST(RowParts, ARigidNormalRowBouncesOnlyWhereItClosesFasterThanTheThreshold) {
  using T = TypeParam;
  SolverFeatherstoneSettings p;
  p.restitution_threshold = 0.2;
  const T dt = T(0.01);
  // approaching at 1 m/s with 0.5 restitution from a gap of 1 mm: a bounce at 0.5 m/s
  EXPECT_NEAR(ContactRows::rigid_normal_target<T>(T(-0.001), T(-1), T(0.5), p, dt), T(0.5), 1e-6);
  // slower than the threshold: the gap closes in the step
  EXPECT_NEAR(ContactRows::rigid_normal_target<T>(T(-0.001), T(-0.1), T(0.5), p, dt), T(-0.1), 1e-6);
  // penetrating 11 mm: erp (0.2) of the 10 mm past the slop per step
  EXPECT_NEAR(ContactRows::rigid_normal_target<T>(T(0.011), T(0), T(0), p, dt), T(0.2), 1e-5);
}

TYPED_TEST(RowParts, AContactKeepsItsRowsImpulsesAsWorldVectorsAndDropsOnesNotFinite) {
  using T = TypeParam;
  using V = Lanes<T>;
  T n[3] = {T(0), T(0.6), T(0.8)}, d[9];
  contact_frame(n, d);
  const T lambda[6] = {T(2), T(0.3), T(-0.4), T(0.05), T(0.01), T(-0.02)};
  T P[6];
  ContactRows::keep(lambda, 6, d, P);
  // the world vectors along the frame give the impulses back (the frame is orthonormal)
  for (int e = 0; e < 6; ++e) {
    const T* axis = d + 3 * (e % 3);
    const T* x = P + (e < 3 ? 0 : 3);
    EXPECT_NEAR(x[0] * axis[0] + x[1] * axis[1] + x[2] * axis[2], lambda[e], 1e-5) << "row " << e;
  }
  // with three rows the spin impulse is 0; a NaN drops its vector in its lane only (the last)
  ContactRows::keep(lambda, 3, d, P);
  for (int m = 3; m < 6; ++m) EXPECT_EQ(P[m], T(0));
  constexpr int kNaNLane = kLanes<T> - 1;
  V lanes[6], dv[9], Pv[6];
  for (int e = 0; e < 6; ++e) lanes[e] = lanes_of<T>([&](int l) { return l == kNaNLane && e == 1 ? kNaN : lambda[e]; });
  for (int m = 0; m < 9; ++m) dv[m] = splat<V>(d[m]);
  ContactRows::keep(lanes, 6, dv, Pv);
  ContactRows::keep(lambda, 6, d, P);
  for (int l = 0; l < kLanes<T>; ++l)
    for (int m = 0; m < 6; ++m) expect_lane<T>(Pv[m], l, l == kNaNLane && m < 3 ? T(0) : P[m], "kept");
}

TEST(RowParts, AContactsRowsAreANormalThenItsFrictionRowsInOneCone) {
  Scalar d[9];
  for (int m = 0; m < 9; ++m) d[m] = m;
  const int direction[6] = {0, 3, 6, 0, 3, 6};
  for (int e = 0; e < 6; ++e) {
    // three rows: the sliding pair as a disk; four or six: every friction row in one cone
    if (e < 3) {
      EXPECT_EQ(ContactRows::kind(e, 3), e == 0 ? RowKind::Unilateral : RowKind::FrictionPair) << "row " << e;
    }
    for (const int dims : {4, 6}) {
      EXPECT_EQ(ContactRows::kind(e, dims), e == 0 ? RowKind::Unilateral : RowKind::FrictionCone) << "row " << e;
    }
    EXPECT_EQ(ContactRows::turns(e), e >= 3) << "row " << e;
    EXPECT_EQ(ContactRows::direction(d, e), d + direction[e]) << "row " << e;
  }
}

}  // namespace
}  // namespace novaphy
