// Spatial tendons' geometry (engine/model/spatial_tendon.h) against closed forms: a path around a sphere and a
// cylinder (tangent, arc, tangent; a helix on the cylinder), a side site choosing the way round, a pulley halving
// the path after it, and a tendon's velocity as the finite difference of its length. MuJoCo's own lengths, forces
// and motions on the same MJCF: tests/python/test_spatial_tendons.py.
#include "engine/model/spatial_tendon.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/model/body_kinematics.h"
#include "engine/model/builder.h"

namespace novaphy {
namespace {

constexpr Scalar kPi = 3.14159265358979323846;

Transform at(Scalar x, Scalar y, Scalar z) {
  Transform T;
  T.p = Vec3(x, y, z);
  return T;
}

// the path from (-a, 0, 0) to (a cos phi, a sin phi, h) round the wrapping geom of radius r at the origin (a
// cylinder's axis z; h = 0 for the sphere): tangents of length sqrt(a^2 - r^2) and the arc between the tangent
// points, the angle between the ends less acos(r / a) for each tangent; a helix on the cylinder
TEST(SpatialTendon, WrapAroundASphereOrCylinderIsTangentArcTangent) {
  const Scalar a = 0.3, r = 0.1, h = 0.2, phi = 0.3;
  const Scalar tangent = std::sqrt(a * a - r * r);
  for (const TendonPathKind kind : {TendonPathKind::Sphere, TendonPathKind::Cylinder}) {
    const Scalar z = kind == TendonPathKind::Cylinder ? h : 0;
    const Vec3 x0(-a, 0, 0), x1(a * std::cos(phi), a * std::sin(phi), z);
    // over the top (the side site above): the short way, pi - phi round; below: the long way, pi + phi
    for (const Scalar side_y : {1.0, -1.0}) {
      const Vec3 side(0, side_y, 0);
      const Scalar arc = r * (kPi - side_y * phi - 2 * std::acos(r / a));
      const Scalar planar = 2 * tangent + arc, climb = z * arc / planar;
      Vec3 w0, w1;
      const Scalar length = wrap_around(kind, Transform::identity(), r, x0, x1, &side, w0, w1);
      EXPECT_NEAR(length, std::hypot(arc, climb), 1e-14);
      EXPECT_NEAR(w0.head<2>().norm(), r, 1e-14);
      EXPECT_NEAR(w1.head<2>().norm(), r, 1e-14);
      EXPECT_GT(side_y * w0.y(), 0);  // (on the side site's side)
      EXPECT_NEAR((w0 - x0).head<2>().norm(), tangent, 1e-14);
      EXPECT_NEAR((w1 - x1).head<2>().norm(), tangent, 1e-14);
    }
  }
}

TEST(SpatialTendon, AStraightPieceClearOfTheGeomWrapsOnlyToPassOnItsSideSitesSide) {
  const Scalar r = 0.1, L = std::hypot(1.0, 0.2), beta = std::atan(0.2);
  const Vec3 x0(-1, 0.2, 0), x1(1, 0.2, 0);
  Vec3 w0, w1;
  EXPECT_EQ(wrap_around(TendonPathKind::Sphere, at(0, 0, 0), r, x0, x1, nullptr, w0, w1), -1);
  const Vec3 above(0, 1, 0), below(0, -1, 0);
  EXPECT_EQ(wrap_around(TendonPathKind::Sphere, at(0, 0, 0), r, x0, x1, &above, w0, w1), -1);
  // the side site below: under the geom, between the lower tangent points
  EXPECT_NEAR(wrap_around(TendonPathKind::Sphere, at(0, 0, 0), r, x0, x1, &below, w0, w1),
              r * (kPi + 2 * beta - 2 * std::acos(r / L)), 1e-14);
  EXPECT_LT(w0.y(), 0);
  EXPECT_LT(w1.y(), 0);
}

// a two-link arm with a tendon from the world over a pulley: site, site | pulley | site, site
Model pulley_arm() {
  ModelBuilder b;
  RigidBody link;
  link.mass = 1;
  link.inertia = Mat3::Identity() * 0.01;
  const int upper = b.add_body(link), lower = b.add_body(link, at(0.4, 0, 0));
  JointOptions hinge;
  hinge.dof.axis = Vec3::UnitY();
  b.add_joint(JointType::Revolute, -1, upper, hinge);
  hinge.parent_xform = at(0.4, 0, 0);
  b.add_joint(JointType::Revolute, upper, lower, hinge);
  auto site = [](int body, Scalar x, Scalar z) {
    return TendonPathElement{TendonPathKind::Site, body, at(x, 0, z), 0};
  };
  b.add_spatial_tendon({site(-1, 0, 0.5),
                        site(upper, 0.2, 0.03),
                        {TendonPathKind::Pulley, -1, {}, 2},
                        site(-1, 0, 0.5),
                        site(lower, 0.3, 0.02)});
  return b.finalize();
}

TEST(SpatialTendon, APulleyDividesThePathAfterIt) {
  const Model model = pulley_arm();
  State state = model.state();
  std::vector<TendonSpan> spans;
  const Scalar length = spatial_tendon(model, 0, state.body_q.data(), spans);
  const Vec3 anchor(0, 0, 0.5), upper(0.2, 0, 0.03), lower(0.7, 0, 0.02);
  EXPECT_NEAR(length, (upper - anchor).norm() + (lower - anchor).norm() / 2, 1e-15);
  ASSERT_EQ(spans.size(), 2u);
  EXPECT_EQ(spans[1].scale, 0.5);
  EXPECT_EQ(model.tendon_rest_length[0], length);  // (NaN given: the length at joint_q0)
}

TEST(SpatialTendon, VelocityIsTheLengthsRateOfChange) {
  const Model model = pulley_arm();
  State state = model.state();
  state.joint_q = {0.3, -0.7};
  state.joint_qd = {1.1, -0.4};
  bodies_from_joints(model, state);
  std::vector<TendonSpan> spans;
  spatial_tendon(model, 0, state.body_q.data(), spans);
  const Scalar v = spatial_tendon_velocity(model, spans, state.body_q.data(), state.body_qd.data());
  const Scalar h = 1e-6;
  auto length_at = [&](Scalar t) {
    State s = state;
    for (int k = 0; k < 2; ++k) s.joint_q[k] += t * state.joint_qd[k];
    bodies_from_joints(model, s);
    std::vector<TendonSpan> at;
    return spatial_tendon(model, 0, s.body_q.data(), at);
  };
  EXPECT_NEAR(v, (length_at(h) - length_at(-h)) / (2 * h), 1e-8);
}

}  // namespace
}  // namespace novaphy
