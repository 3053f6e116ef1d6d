// The convex narrow phase (kernels/convex) and hulls (kernels/hull) against closed forms and the primitive kernels.
#include "kernels/convex.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "kernels/hull.h"
#include "test_support.h"

namespace novaphy {
namespace {

ConvexShape shape(ConvexKind kind, const Vec3& p, const Vec3& size, const Quat& q = Quat::Identity()) {
  return {kind, Transform{p, q}, size, nullptr};
}

TEST(CollideConvex, SpheresAsTheClosedForm) {
  ContactPoint out[4];
  const Vec3 b(0.1, 0.15, -0.05);
  ASSERT_EQ(collide_convex(shape(ConvexKind::Sphere, Vec3::Zero(), Vec3::Constant(0.1)),
                           shape(ConvexKind::Sphere, b, Vec3::Constant(0.12)), 0, out),
            1);
  EXPECT_NEAR(out[0].depth, 0.22 - b.norm(), 1e-6);
  EXPECT_GT(out[0].normal.dot(b.normalized()), 1 - 1e-6);
}

TEST(CollidePlaneCylinder, StandingFourRimPointsLyingTwo) {
  ContactPoint out[kMaxPairContacts];
  const Transform ground;
  // standing on a cap, 1 mm deep: four rim points of the lower cap at the same depth
  ASSERT_EQ(collide_plane_cylinder(ground, Transform{Vec3(0.3, 0.049, -0.2), Quat::Identity()}, 0.1, 0.05, 0.01, out),
            4);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(out[k].depth, 0.001, 1e-12);
    EXPECT_NEAR((out[k].point - Vec3(0.3, 0, -0.2)).norm(), 0.1, 1e-3);
  }
  // lying on its side: the line of contact's two ends
  const Quat side(Eigen::AngleAxis<Scalar>(M_PI / 2, Vec3::UnitX()));
  ASSERT_EQ(collide_plane_cylinder(ground, Transform{Vec3(0, 0.098, 0), side}, 0.1, 0.15, 0.01, out), 2);
  EXPECT_NEAR(out[0].depth, 0.002, 1e-12);
  EXPECT_NEAR(out[1].depth, 0.002, 1e-12);
  EXPECT_NEAR(std::abs(out[0].point.z() - out[1].point.z()), 0.3, 1e-12);
  // tipped onto its rim: one point, as deep as the rim reaches
  const Scalar tilt = 0.4;
  const Transform tipped{Vec3(0, 0.08, 0), Quat(Eigen::AngleAxis<Scalar>(tilt, Vec3::UnitZ()))};
  const Scalar lowest = 0.08 - (0.05 * std::cos(tilt) + 0.1 * std::sin(tilt));
  ASSERT_GE(collide_plane_cylinder(ground, tipped, 0.1, 0.05, 0, out), 1);
  EXPECT_NEAR(out[0].depth, -lowest, 1e-12);
}

TEST(CollidePlaneEllipsoid, DeepestPointAsTheClosedForm) {
  // an ellipsoid turned by theta about Z reaches sqrt((a sin)^2 + (b cos)^2) below its centre
  const Vec3 radii(0.2, 0.1, 0.15);
  for (const Scalar theta : {0.0, 0.3, 1.1}) {
    const Transform pose{Vec3(0, 0.1, 0), Quat(Eigen::AngleAxis<Scalar>(theta, Vec3::UnitZ()))};
    ContactPoint out[1];
    ASSERT_EQ(collide_plane_ellipsoid(Transform{}, pose, radii, 1, out), 1);
    const Scalar reach = std::hypot(radii.x() * std::sin(theta), radii.y() * std::cos(theta));
    EXPECT_NEAR(out[0].depth, reach - 0.1, 1e-12) << theta;
    EXPECT_EQ(out[0].normal, Vec3::UnitY());
  }
}

// a box's corners, and a point inside it (not a vertex of its hull)
std::vector<Vec3> box_points(const Vec3& half) {
  std::vector<Vec3> corners;
  for (int v = 0; v < 8; ++v)
    corners.push_back(half.cwiseProduct(Vec3(v & 1 ? 1 : -1, v & 2 ? 1 : -1, v & 4 ? 1 : -1)));
  corners.push_back(Vec3::Zero());  // (inside: not a vertex of the hull)
  return corners;
}

TEST(ConvexHull, BoxCornersGiveSixSquareFacesCounterclockwise) {
  const Vec3 half(0.3, 0.2, 0.1);
  const test::HullArrays cube(box_points(half));
  EXPECT_EQ(cube.hull.vertex.size(), 8u);
  ASSERT_EQ(cube.hull.face_count(), 6);
  for (int f = 0; f < 6; ++f) {
    ASSERT_EQ(cube.hull.corner_start[f + 1] - cube.hull.corner_start[f], 4);
    const Vec3& n = cube.hull.face_normal[f];
    EXPECT_NEAR(n.cwiseAbs().maxCoeff(), 1, 1e-12);
    int k;
    n.cwiseAbs().maxCoeff(&k);
    EXPECT_NEAR(cube.hull.face_offset[f], half[k], 1e-12);
    const int* c = &cube.hull.corner[cube.hull.corner_start[f]];
    const Vec3 turn =
        (cube.hull.vertex[c[1]] - cube.hull.vertex[c[0]]).cross(cube.hull.vertex[c[2]] - cube.hull.vertex[c[1]]);
    EXPECT_GT(turn.dot(n), 0) << "face " << f << " counterclockwise seen from outside";
  }
}

TEST(ConvexHull, DegenerateInputSaysWhy) {
  ConvexHull hull;
  EXPECT_EQ(convex_hull({Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()}, &hull), "a hull needs at least 4 points, got 3");
  EXPECT_EQ(convex_hull({Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY(), Vec3(NAN, 0, 0)}, &hull), "point 3 is not finite");
  const std::string flat = convex_hull({Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY(), Vec3(1, 1, 0)}, &hull);
  EXPECT_EQ(flat.rfind("the points span no volume (all on one plane or line; qhull: ", 0), 0u) << flat;
}

// a box's hull collides as the box: on the plane as collide_plane_box, against a box as collide_box_box
TEST(CollideConvex, BoxHullCollidesAsTheBox) {
  const Vec3 half(0.3, 0.2, 0.1);
  const test::HullArrays cube(box_points(half));
  const Transform pose{Vec3(0.1, 0.19, -0.2), Quat(Eigen::AngleAxis<Scalar>(0.02, Vec3(1, 0, 1).normalized()))};
  ContactPoint hull_points[kMaxPairContacts], box_points[kMaxPairContacts];
  const int n = collide_plane_hull(Transform{}, pose, cube.view, 0.01, hull_points);
  ASSERT_EQ(n, collide_plane_box(Transform{}, pose, half, 0.01, box_points));
  ASSERT_EQ(n, 4);
  std::vector<Scalar> hull_depths, box_depths;
  for (int k = 0; k < n; ++k) hull_depths.push_back(hull_points[k].depth), box_depths.push_back(box_points[k].depth);
  std::sort(hull_depths.begin(), hull_depths.end());
  std::sort(box_depths.begin(), box_depths.end());
  for (int k = 0; k < n; ++k) EXPECT_NEAR(hull_depths[k], box_depths[k], 1e-12);
  // on a box below it, tilted a little: the same four depths and normal as the box-box kernel's face manifold
  const Transform below{Vec3(0, -0.5, 0), Quat::Identity()};
  const Vec3 floor_half(1, 0.5, 1);
  const int m = collide_convex(ConvexShape{ConvexKind::Box, below, floor_half, nullptr},
                               ConvexShape{ConvexKind::Hull, pose, Vec3::Zero(), &cube.view}, 0.01, hull_points);
  ASSERT_EQ(m, collide_box_box(below, floor_half, pose, half, 0.01, box_points));
  hull_depths.clear(), box_depths.clear();
  for (int k = 0; k < m; ++k) {
    hull_depths.push_back(hull_points[k].depth), box_depths.push_back(box_points[k].depth);
    EXPECT_NEAR((hull_points[k].normal - box_points[k].normal).norm(), 0, 1e-12);
  }
  std::sort(hull_depths.begin(), hull_depths.end());
  std::sort(box_depths.begin(), box_depths.end());
  for (int k = 0; k < m; ++k) EXPECT_NEAR(hull_depths[k], box_depths[k], 1e-9);
}

// every pair stacked along Y, axis-aligned and centred, 1 mm into each other: the closed form is a depth of 1 mm
// along +Y at every point the pair reports (within MPR's tolerance: 1e-6 m, the normal 0.3 degrees; the mesh: an
// octagonal prism's hull, flat on top and bottom)
TEST(CollideConvex, StackedPairsOverlapByTheirClosedForm) {
  const test::HullArrays prism(test::prism_points(8, 0.1, 0.05));
  const HullView& view = prism.view;
  struct Kind {
    const char* name;
    ConvexKind kind;
    Vec3 size;
    Scalar half;  // how far it reaches along Y from its centre
  };
  const Kind kinds[] = {{"sphere", ConvexKind::Sphere, Vec3::Constant(0.08), 0.08},
                        {"box", ConvexKind::Box, Vec3(0.1, 0.06, 0.09), 0.06},
                        {"capsule", ConvexKind::Capsule, Vec3(0.04, 0.05, 0), 0.09},
                        {"cylinder", ConvexKind::Cylinder, Vec3(0.07, 0.05, 0), 0.05},
                        {"ellipsoid", ConvexKind::Ellipsoid, Vec3(0.11, 0.07, 0.09), 0.07},
                        {"mesh", ConvexKind::Hull, Vec3::Zero(), 0.05}};
  for (const Kind& a : kinds)
    for (const Kind& b : kinds) {
      if (a.kind != ConvexKind::Cylinder && a.kind != ConvexKind::Ellipsoid && a.kind != ConvexKind::Hull &&
          b.kind != ConvexKind::Cylinder && b.kind != ConvexKind::Ellipsoid && b.kind != ConvexKind::Hull)
        continue;  // (the primitives' pairs: collide_test)
      const ConvexShape A{a.kind, Transform{}, a.size, &view};
      const ConvexShape B{b.kind, Transform{Vec3(0, a.half + b.half - 0.001, 0), Quat::Identity()}, b.size, &view};
      ContactPoint out[4];
      const int n = collide_convex(A, B, 0, out);
      ASSERT_GE(n, 1) << a.name << "-" << b.name;
      for (int k = 0; k < n; ++k) {
        EXPECT_NEAR(out[k].depth, 0.001, 1e-6) << a.name << "-" << b.name << " point " << k;
        EXPECT_GT(out[k].normal.dot(Vec3::UnitY()), 1 - 1e-5) << a.name << "-" << b.name << " point " << k;
      }
    }
}

// a hull whose face has more corners than a feature holds (a 40-gon prism) lying on a box: its contacts spread
// round the whole face, their middle at the face's centre
TEST(CollideConvex, AManyCorneredFaceRestsOnAllOfIt) {
  const test::HullArrays prism(test::prism_points(40, 0.1, 0.05));
  const ConvexShape floor{ConvexKind::Box, Transform{Vec3(0, -0.5, 0), Quat::Identity()}, Vec3(1, 0.5, 1), nullptr};
  const ConvexShape disk{ConvexKind::Hull, Transform{Vec3(0.2, 0.049, -0.1), Quat::Identity()}, Vec3::Zero(),
                         &prism.view};
  ContactPoint out[4];
  ASSERT_EQ(collide_convex(floor, disk, 0, out), 4);
  Vec3 middle = Vec3::Zero();
  for (const ContactPoint& c : out) {
    EXPECT_NEAR(c.depth, 0.001, 1e-9);
    EXPECT_NEAR((c.point - Vec3(0.2, 0, -0.1)).norm(), 0.1, 1e-3);  // on the rim
    middle += c.point / 4;
  }
  EXPECT_LT((middle - Vec3(0.2, 0, -0.1)).norm(), 0.03);
}

// a sphere beside a cylinder's side, and against its cap: the closed forms
TEST(CollideConvex, SphereOnCylinderSideAndCap) {
  const ConvexShape cylinder{ConvexKind::Cylinder, Transform{}, Vec3(0.1, 0.2, 0), nullptr};
  ContactPoint out[4];
  ASSERT_EQ(collide_convex(cylinder, shape(ConvexKind::Sphere, Vec3(0.14, 0.05, 0), Vec3::Constant(0.05)), 0, out), 1);
  EXPECT_NEAR(out[0].depth, 0.01, 1e-6);
  EXPECT_GT(out[0].normal.dot(Vec3::UnitX()), 1 - 1e-6);
  ASSERT_EQ(collide_convex(cylinder, shape(ConvexKind::Sphere, Vec3(0.02, 0.23, 0.01), Vec3::Constant(0.05)), 0, out),
            1);
  EXPECT_NEAR(out[0].depth, 0.02, 1e-6);
  EXPECT_GT(out[0].normal.dot(Vec3::UnitY()), 1 - 1e-6);
}

TEST(CollideConvex, AnExtremePairEndsItsSearch) {
  // fuzz_builder's finding: a cylinder of 1e-12 inside an ellipsoid of semi-axes 0.76 and 1e12, at one pose. libccd's
  // portal search, unbounded but for its last phase, cycled without end on it in the clang build; the support calls
  // a query makes are now bounded. Whatever it answers, it answers, and any contact it reports is finite
  const Quat q(-0.57735026918962584, -0.57735026918962584, -0.57735026918962584, 5.7735026918962581e-13);
  const Vec3 at(1e-12, 0, 1e-12);
  const ConvexShape tiny{ConvexKind::Cylinder, Transform{at, q}, Vec3::Constant(1e-12), nullptr};
  const ConvexShape huge{ConvexKind::Ellipsoid, Transform{at, q}, Vec3(0.76317647058845073, 1e12, 0.76317647058845073),
                         nullptr};
  ContactPoint out[4];
  for (const auto& [a, b] : {std::pair{&tiny, &huge}, {&huge, &tiny}}) {
    const int count = collide_convex(*a, *b, 0.01, out);
    for (int k = 0; k < count; ++k) EXPECT_TRUE(out[k].point.allFinite() && out[k].normal.allFinite());
  }
}

}  // namespace
}  // namespace novaphy
