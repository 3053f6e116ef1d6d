#include "kernels/collide.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <set>

#include "kernels/convex.h"

namespace novaphy {
namespace {

Quat about(const Vec3& axis, Scalar angle) { return Quat(Eigen::AngleAxis<Scalar>(angle, axis.normalized())); }

TEST(Collide, SphereOnPlane) {
  ContactPoint c[kMaxPairContacts];
  ASSERT_EQ(collide_plane_sphere(Transform{Vec3::Zero()}, Vec3(1, 0.4, 2), 0.5, 0.01, c), 1);
  EXPECT_NEAR(c[0].depth, 0.1, 1e-15);
  EXPECT_EQ(c[0].normal, Vec3::UnitY());
  EXPECT_LT((c[0].point - Vec3(1, -0.05, 2)).norm(), 1e-15);  // midway between the surfaces
  EXPECT_EQ(collide_plane_sphere(Transform{Vec3::Zero()}, Vec3(0, 0.52, 0), 0.5, 0.01, c), 0);
}

// the lanes of plane_sphere_contact are collide_plane_sphere's bits, lane by lane: tilted planes, spheres above,
// touching and below them, margins from none to 5 cm
TEST(Collide, SpheresOnPlanesInLanesAreTheScalarKernelsLaneByLane) {
  using V = Lanes<Scalar>;
  constexpr int L = kLanes<Scalar>;
  std::mt19937 rng(3);
  std::uniform_real_distribution<Scalar> unit(-1, 1);
  int touching = 0, apart = 0;
  for (int round = 0; round < 50; ++round) {
    Transform plane[L];
    Vec3 center[L];
    V o[3], n[3], c[3], r, margin;
    for (int l = 0; l < L; ++l) {
      plane[l] =
          Transform{Vec3(unit(rng), unit(rng), unit(rng)), about(Vec3(unit(rng), unit(rng), unit(rng)), unit(rng))};
      const Vec3 normal = plane[l].q * Vec3::UnitY();
      r[l] = 0.05 + 0.05 * (unit(rng) + 1);
      margin[l] = 0.025 * (unit(rng) + 1);
      center[l] = plane[l].p + 2 * Vec3(unit(rng), unit(rng), unit(rng)) + normal * (r[l] + 0.1 * unit(rng));
      for (int m = 0; m < 3; ++m) o[m][l] = plane[l].p[m], n[m][l] = normal[m], c[m][l] = center[l][m];
    }
    V point[3], depth;
    const IntLanes<Scalar> on = plane_sphere_contact<V>(o, n, c, r, margin, point, &depth);
    for (int l = 0; l < L; ++l) {
      ContactPoint expected[kMaxPairContacts];
      const int count = collide_plane_sphere(plane[l], center[l], r[l], margin[l], expected);
      ASSERT_EQ(on[l] != 0, count == 1) << "round " << round << " lane " << l;
      (count ? touching : apart) += 1;
      if (!count) continue;
      EXPECT_EQ(depth[l], expected[0].depth);
      for (int m = 0; m < 3; ++m) EXPECT_EQ(point[m][l], expected[0].point[m]);
    }
  }
  EXPECT_GT(touching, 50);
  EXPECT_GT(apart, 50);
}

TEST(Collide, BoxRestingOnPlaneTouchesAtFourCorners) {
  ContactPoint c[kMaxPairContacts];
  const int n = collide_plane_box(Transform{Vec3::Zero()}, Transform{Vec3(0, 0.19, 0), about(Vec3::UnitY(), 0.3)},
                                  Vec3(0.2, 0.2, 0.2), 0.005, c);
  ASSERT_EQ(n, 4);
  std::set<int> features;
  for (int k = 0; k < n; ++k) {
    EXPECT_NEAR(c[k].depth, 0.01, 1e-14);
    features.insert(c[k].feature);
  }
  EXPECT_EQ(features.size(), 4u);
}

TEST(Collide, StackedBoxesGiveFourPointsWithStableFeatures) {
  ContactPoint c[kMaxPairContacts], d[kMaxPairContacts];
  const Vec3 h(0.2, 0.2, 0.2);
  const int n = collide_box_box(Transform{Vec3::Zero()}, h, Transform{Vec3(0.05, 0.395, 0)}, h, 0.01, c);
  ASSERT_EQ(n, 4);
  for (int k = 0; k < n; ++k) {
    EXPECT_LT((c[k].normal - Vec3::UnitY()).norm(), 1e-12);
    EXPECT_NEAR(c[k].depth, 0.005, 1e-12);
  }
  // a small shift keeps the same features
  ASSERT_EQ(collide_box_box(Transform{Vec3::Zero()}, h, Transform{Vec3(0.051, 0.3951, 0)}, h, 0.01, d), 4);
  std::set<int> fc, fd;
  for (int k = 0; k < 4; ++k) fc.insert(c[k].feature), fd.insert(d[k].feature);
  EXPECT_EQ(fc, fd);
  // seen from the other box: same depths, opposite normals
  ASSERT_EQ(collide_box_box(Transform{Vec3(0.05, 0.395, 0)}, h, Transform{Vec3::Zero()}, h, 0.01, d), 4);
  for (int k = 0; k < 4; ++k) EXPECT_LT((d[k].normal + Vec3::UnitY()).norm(), 1e-12);
}

TEST(Collide, CrossedBoxEdgesTouchAtOnePoint) {
  ContactPoint c[kMaxPairContacts];
  // two long bars rotated 45 degrees about their axes, crossing at right angles, edges touching
  const Vec3 h(1, 0.1, 0.1);
  const Transform a = Transform{Vec3::Zero(), about(Vec3::UnitX(), M_PI / 4)};
  const Transform b = Transform{Vec3(0, 0.1 * std::sqrt(8.0) - 0.01, 0),
                                about(Vec3::UnitY(), M_PI / 2) * about(Vec3::UnitX(), M_PI / 4)};
  ASSERT_EQ(collide_box_box(a, h, b, h, 0.001, c), 1);
  EXPECT_LT((c[0].normal - Vec3::UnitY()).norm(), 1e-9);
  EXPECT_NEAR(c[0].depth, 0.01, 1e-9);
  EXPECT_LT(c[0].point.norm() - 0.1 * std::sqrt(2.0), 1e-9);
}

TEST(Collide, CapsuleLyingOnBoxTouchesAtBothEnds) {
  ContactPoint c[kMaxPairContacts];
  // capsule along x (local Y rotated onto x), resting on a wide box
  const Transform capsule = Transform{Vec3(0, 0.145, 0), about(Vec3::UnitZ(), M_PI / 2)};
  const int n = collide_capsule_box(capsule, 0.05, 0.3, Transform{Vec3::Zero()}, Vec3(1, 0.1, 1), 0.01, c);
  ASSERT_EQ(n, 2);
  for (int k = 0; k < n; ++k) {
    EXPECT_NEAR(c[k].depth, 0.005, 1e-9);
    EXPECT_LT((c[k].normal + Vec3::UnitY()).norm(), 1e-9);  // from the capsule down into the box
  }
  EXPECT_NE(c[0].feature, c[1].feature);
}

TEST(Collide, CapsulesCrossedAndParallel) {
  ContactPoint c[kMaxPairContacts];
  const Transform a = Transform{Vec3::Zero(), about(Vec3::UnitZ(), M_PI / 2)};
  const Transform crossed = Transform{Vec3(0, 0.19, 0), about(Vec3::UnitX(), M_PI / 2)};
  ASSERT_EQ(collide_capsule_capsule(a, 0.1, 0.5, crossed, 0.1, 0.5, 0.01, c), 1);
  EXPECT_NEAR(c[0].depth, 0.01, 1e-12);
  const Transform parallel = Transform{Vec3(0, 0.19, 0), about(Vec3::UnitZ(), M_PI / 2)};
  EXPECT_EQ(collide_capsule_capsule(a, 0.1, 0.5, parallel, 0.1, 0.5, 0.01, c), 2);
}

TEST(Collide, SphereInsideBoxIsDeep) {
  ContactPoint c[kMaxPairContacts];
  ASSERT_EQ(collide_sphere_box(Vec3(0, 0.15, 0), 0.1, Transform{Vec3::Zero()}, Vec3(0.5, 0.2, 0.5), 0.01, c), 1);
  EXPECT_NEAR(c[0].depth, 0.15, 1e-12);                    // 0.05 inside the top face plus the radius
  EXPECT_LT((c[0].normal + Vec3::UnitY()).norm(), 1e-12);  // from the sphere into the box
}

// the deepest point is no deeper than the boxes overlap along the contact normal, and that normal's
// overlap is the smallest over the separating axes up to the preference given to face axes
TEST(Collide, BoxBoxDepthMatchesSupportScan) {
  std::mt19937 rng(9);
  std::normal_distribution<Scalar> g;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 ha(0.1 + 0.3 * std::abs(g(rng)), 0.1 + 0.3 * std::abs(g(rng)), 0.1 + 0.3 * std::abs(g(rng)));
    const Vec3 hb(0.1 + 0.3 * std::abs(g(rng)), 0.1 + 0.3 * std::abs(g(rng)), 0.1 + 0.3 * std::abs(g(rng)));
    const Transform a = Transform{Vec3::Zero(), Quat(g(rng), g(rng), g(rng), g(rng)).normalized()};
    const Transform b =
        Transform{0.4 * Vec3(g(rng), g(rng), g(rng)), Quat(g(rng), g(rng), g(rng), g(rng)).normalized()};
    ContactPoint c[kMaxPairContacts];
    const int n = collide_box_box(a, ha, b, hb, 0, c);
    // minimum over many directions of the overlap of the two projections (>= the SAT minimum)
    Scalar scan = std::numeric_limits<Scalar>::infinity();
    const Mat3 Ra = a.rotation(), Rb = b.rotation();
    auto overlap = [&](const Vec3& L) {
      const Scalar pa = (Ra.transpose() * L).cwiseAbs().dot(ha), pb = (Rb.transpose() * L).cwiseAbs().dot(hb);
      return pa + pb - std::abs((b.p - a.p).dot(L));
    };
    for (int k = 0; k < 3; ++k) scan = std::min({scan, overlap(Ra.col(k)), overlap(Rb.col(k))});
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const Vec3 L = Ra.col(i).cross(Rb.col(j));
        if (L.norm() > 1e-6) scan = std::min(scan, overlap(L.normalized()));
      }
    if (scan < 0) {
      EXPECT_EQ(n, 0) << "trial " << trial;
      continue;
    }
    ASSERT_GT(n, 0) << "trial " << trial;
    Scalar deepest = 0;
    for (int k = 0; k < n; ++k) deepest = std::max(deepest, c[k].depth);
    const Scalar along_normal = overlap(c[0].normal);
    const Scalar face_preference = 1e-3 * (ha.minCoeff() + hb.minCoeff());
    EXPECT_LE(deepest, along_normal + 1e-9) << "trial " << trial;
    EXPECT_LE(along_normal, (scan + face_preference) / 0.95 + 1e-9) << "trial " << trial;
    EXPECT_GT(deepest, 0) << "trial " << trial;
  }
}

TEST(Collide, BoxesApartWhereAnAxisSeparatesThemAndNeverWhereMprFindsContact) {
  // random pairs of boxes near each other, margin 2 cm: boxes_apart where one of the fifteen axes, normalised,
  // separates their projections by more than the margin, and then libccd's MPR finds no contact within it
  std::mt19937 rng(5);
  std::normal_distribution<Scalar> g;
  const Scalar margin = 0.02;
  int apart = 0, near = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 ha(0.05 + 0.2 * std::abs(g(rng)), 0.05 + 0.2 * std::abs(g(rng)), 0.05 + 0.2 * std::abs(g(rng)));
    const Vec3 hb(0.05 + 0.2 * std::abs(g(rng)), 0.05 + 0.2 * std::abs(g(rng)), 0.05 + 0.2 * std::abs(g(rng)));
    const Transform a{0.3 * Vec3(g(rng), g(rng), g(rng)), Quat(g(rng), g(rng), g(rng), g(rng)).normalized()};
    const Transform b{0.3 * Vec3(g(rng), g(rng), g(rng)) + Vec3(0.4, 0, 0),
                      Quat(g(rng), g(rng), g(rng), g(rng)).normalized()};
    const Mat3 Ra = a.rotation(), Rb = b.rotation();
    Scalar gap = -std::numeric_limits<Scalar>::infinity();
    auto separate = [&](Vec3 L) {
      L.normalize();
      const Scalar pa = (Ra.transpose() * L).cwiseAbs().dot(ha), pb = (Rb.transpose() * L).cwiseAbs().dot(hb);
      gap = std::max(gap, std::abs((b.p - a.p).dot(L)) - pa - pb);
    };
    for (int k = 0; k < 3; ++k) separate(Ra.col(k)), separate(Rb.col(k));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (Ra.col(i).cross(Rb.col(j)).norm() > 1e-6) separate(Ra.col(i).cross(Rb.col(j)));
    if (std::abs(gap - margin) < 1e-9) continue;
    const bool is_apart = boxes_apart(a, ha, b, hb, margin);
    EXPECT_EQ(is_apart, gap > margin) << "trial " << trial;
    ContactPoint c[kMaxPairContacts];
    if (is_apart)
      EXPECT_EQ(collide_convex({ConvexKind::Box, a, ha}, {ConvexKind::Box, b, hb}, margin, c), 0) << "trial " << trial;
    (is_apart ? apart : near) += 1;
  }
  EXPECT_GT(apart, 80);
  EXPECT_GT(near, 80);
}

TEST(Collide, BoxBoxFeaturesAreDistinctWithinAPair) {
  // warm starts find a contact by its pair and feature: no two points of one pair may share one (a
  // clipped point's id once came from its index in the clipped polygon, and repeated)
  std::mt19937 rng(12);
  std::normal_distribution<Scalar> g;
  int multi = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 ha(0.1 + 0.2 * std::abs(g(rng)), 0.1 + 0.2 * std::abs(g(rng)), 0.1 + 0.2 * std::abs(g(rng)));
    const Vec3 hb(0.1 + 0.2 * std::abs(g(rng)), 0.1 + 0.2 * std::abs(g(rng)), 0.1 + 0.2 * std::abs(g(rng)));
    // b tilted a little from a's axes and resting on one of a's faces, slid sideways
    const Quat tilt = about(Vec3(g(rng), g(rng), g(rng)), 0.15 * g(rng));
    const int axis = trial % 3;
    Vec3 offset = 0.3 * Vec3(g(rng), g(rng), g(rng));
    offset[axis] = (trial % 2 ? 1 : -1) * (ha[axis] + hb[axis] - 0.01);
    ContactPoint c[kMaxPairContacts];
    const int n = collide_box_box(Transform{Vec3::Zero()}, ha, Transform{offset, tilt}, hb, 0.01, c);
    multi += n > 2;
    std::set<int> features;
    for (int k = 0; k < n; ++k) features.insert(c[k].feature);
    EXPECT_EQ(features.size(), static_cast<size_t>(n)) << "trial " << trial;
  }
  EXPECT_GT(multi, 500);  // face contacts, clipped, were seen
}

// a random pose [p, q] (q unit, [x y z w]) and a shape's sizes
void random_pose(std::mt19937& rng, Scalar* x) {
  std::normal_distribution<Scalar> g;
  const Quat q = Quat(g(rng), g(rng), g(rng), g(rng)).normalized();
  Transform{Vec3(g(rng), g(rng), g(rng)), q}.to_array(x);
}

constexpr BoundsKind kKinds[] = {BoundsKind::Plane, BoundsKind::Sphere, BoundsKind::Box, BoundsKind::Capsule};

TEST(ShapeBounds, InLanesEqualTheirTwinBitForBit) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<Scalar> size(0.01, 2);
  for (int trial = 0; trial < 200; ++trial) {
    Lanes<Scalar> body[7], local[7], scale[3], pose[2][7], lower[2][3], upper[2][3];
    for (int l = 0; l < kLanes<Scalar>; ++l) {
      Scalar b[7], x[7];
      random_pose(rng, b);
      random_pose(rng, x);
      for (int k = 0; k < 7; ++k) body[k][l] = b[k], local[k][l] = x[k];
      for (int k = 0; k < 3; ++k) scale[k][l] = size(rng);
    }
    const BoundsKind kind = kKinds[trial % 4];
    shape_bounds(kind, body, local, scale, 0.01, pose[0], lower[0], upper[0]);
    shape_bounds_lanes_reference(kind, body, local, scale, 0.01, pose[1], lower[1], upper[1]);
    for (int l = 0; l < kLanes<Scalar>; ++l) {
      for (int k = 0; k < 7; ++k) EXPECT_EQ(pose[0][k][l], pose[1][k][l]) << "trial " << trial;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(lower[0][k][l], lower[1][k][l]) << "trial " << trial;
        EXPECT_EQ(upper[0][k][l], upper[1][k][l]) << "trial " << trial;
      }
    }
  }
}

// the pose is the product of the transforms; the bounds hold the shape and touch it on every side:
// the box's corners, the capsule's end spheres, the sphere, measured against Eigen's rotation
TEST(ShapeBounds, AreThePosesProductAndTheShapesTightBox) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<Scalar> size(0.01, 2);
  for (int trial = 0; trial < 400; ++trial) {
    Scalar b[7], x[7], p[7], lower[3], upper[3];
    random_pose(rng, b);
    random_pose(rng, x);
    const Scalar scale[3] = {size(rng), size(rng), size(rng)}, margin = 0.01;
    const BoundsKind kind = kKinds[trial % 4];
    shape_bounds(kind, b, x, scale, margin, p, lower, upper);
    const Transform expected = Transform::from_array(b) * Transform::from_array(x), pose = Transform::from_array(p);
    EXPECT_LT((pose.p - expected.p).norm(), 1e-14) << "trial " << trial;
    EXPECT_LT((pose.q.coeffs() - expected.q.coeffs()).norm(), 1e-15) << "trial " << trial;
    const Mat3 R = expected.rotation();
    Vec3 extent = Vec3::Zero();  // the farthest the shape reaches from its origin along each axis
    if (kind == BoundsKind::Sphere) extent.setConstant(scale[0]);
    if (kind == BoundsKind::Capsule) extent = (R.col(1) * scale[1]).cwiseAbs() + Vec3::Constant(scale[0]);
    if (kind == BoundsKind::Box)
      for (int v = 0; v < 8; ++v) {
        const Vec3 corner((v & 1 ? 1 : -1) * scale[0], (v & 2 ? 1 : -1) * scale[1], (v & 4 ? 1 : -1) * scale[2]);
        extent = extent.cwiseMax((R * corner).cwiseAbs());
      }
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(lower[k], expected.p[k] - extent[k] - margin, 1e-13) << "trial " << trial << " axis " << k;
      EXPECT_NEAR(upper[k], expected.p[k] + extent[k] + margin, 1e-13) << "trial " << trial << " axis " << k;
    }
  }
}

// the distance to a box's nearest point is the least of its corners' distances; in lanes, each lane's
// is the scalar one bit for bit
TEST(ShapeBounds, PlaneBoxDistanceIsTheNearestCornersAndTheSameInLanes) {
  std::mt19937 rng(8);
  std::normal_distribution<Scalar> g;
  for (int trial = 0; trial < 50; ++trial) {
    Lanes<Scalar> origin[3], normal[3], lower[3], upper[3];
    Scalar each[kLanes<Scalar>];
    for (int l = 0; l < kLanes<Scalar>; ++l) {
      const Vec3 p(g(rng), g(rng), g(rng)), n = Vec3(g(rng), g(rng), g(rng)).normalized();
      const Vec3 center(g(rng), g(rng), g(rng)), half = Vec3(g(rng), g(rng), g(rng)).cwiseAbs();
      const Vec3 lo = center - half, up = center + half;
      Scalar nearest = std::numeric_limits<Scalar>::infinity();
      for (int v = 0; v < 8; ++v)
        nearest = std::min(nearest,
                           n.dot(Vec3(v & 1 ? up.x() : lo.x(), v & 2 ? up.y() : lo.y(), v & 4 ? up.z() : lo.z()) - p));
      each[l] = plane_box_distance(p.data(), n.data(), lo.data(), up.data());
      EXPECT_NEAR(each[l], nearest, 1e-14) << "trial " << trial;
      for (int k = 0; k < 3; ++k) origin[k][l] = p[k], normal[k][l] = n[k], lower[k][l] = lo[k], upper[k][l] = up[k];
    }
    const Lanes<Scalar> lanes = plane_box_distance(origin, normal, lower, upper);
    for (int l = 0; l < kLanes<Scalar>; ++l) EXPECT_EQ(lanes[l], each[l]) << "trial " << trial << " lane " << l;
  }
}

}  // namespace
}  // namespace novaphy
