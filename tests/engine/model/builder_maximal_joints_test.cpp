// ModelBuilder's maximal-coordinate joints: the layout of a Distance, D6 and Cable joint (its dofs' ranges, its
// turned frame, its compliance, its start where the bodies were placed) and their bad input, each error named.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/model/builder.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

constexpr Scalar kInf = std::numeric_limits<Scalar>::infinity();

// two boxes, the second placed at `at` (its joint's child), the first hanging from the world by a Revolute joint
struct TwoBodies {
  explicit TwoBodies(const Transform& at = Transform{Vec3(0, -1, 0), Quat::Identity()}) {
    a = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)));
    b = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)), at);
    JointOptions hinge;
    hinge.dof.axis = Vec3::UnitZ();
    builder.add_joint_revolute(-1, a, hinge);
  }
  ModelBuilder builder;
  int a, b;
};

JointDofConfig axis(const Vec3& v, Scalar lower = -kInf, Scalar upper = kInf) {
  JointDofConfig dof;
  dof.axis = v;
  dof.limit_lower = lower;
  dof.limit_upper = upper;
  return dof;
}

TEST(MaximalJoints, D6LaysOutItsAxesAsDofsOfItsTurnedFrame) {
  TwoBodies s;
  // linear along z (limited), angular about x (free): the frame's x is z, its y is x
  s.builder.add_joint_d6(s.a, s.b, {}, {axis(Vec3::UnitZ(), -0.1, 0.2)}, {axis(Vec3::UnitX())}, 1e-3, 2e-3);
  const Model model = s.builder.finalize();
  const int j = 1, d = model.joint_qd_start[j];
  EXPECT_EQ(static_cast<JointType>(model.joint_type[j]), JointType::D6);
  EXPECT_EQ(model.joint_qd_start[j + 1] - d, 6);
  // dofs: angular x, y, z then linear x, y, z of the turned frame
  const Scalar lower[6] = {0, -kInf, 0, -0.1, 0, 0}, upper[6] = {0, kInf, 0, 0.2, 0, 0};
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(model.joint_limit_lower[d + k], lower[k]) << k;
    EXPECT_EQ(model.joint_limit_upper[d + k], upper[k]) << k;
  }
  const Transform X_p = Transform::from_array(&model.joint_X_p[7 * j]);
  EXPECT_LT((X_p.q * Vec3::UnitX() - Vec3::UnitZ()).norm(), 1e-12);
  EXPECT_LT((X_p.q * Vec3::UnitY() - Vec3::UnitX()).norm(), 1e-12);
  EXPECT_EQ(model.joint_compliance[2 * j], 1e-3);
  EXPECT_EQ(model.joint_compliance[2 * j + 1], 2e-3);
  // it starts where its child was placed
  const State state = model.state();
  EXPECT_NEAR(state.body_q[7 * s.b + 1], -1, 1e-12);
}

TEST(MaximalJoints, DistanceAndCableStartWhereTheBodiesWerePlaced) {
  const Transform placed{Vec3(0.3, -0.8, 0.1), Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()))};
  for (const JointType type : {JointType::Distance, JointType::Cable}) {
    TwoBodies s(placed);
    JointOptions options;
    options.parent_xform.p = Vec3(0, -0.1, 0);
    options.child_xform.p = Vec3(0, 0.1, 0);
    if (type == JointType::Distance)
      s.builder.add_joint_distance(s.a, s.b, options, 0.5, 1.0, 0.01);
    else
      s.builder.add_joint_cable(s.a, s.b, options, 0.01, 0.02);
    const Model model = s.builder.finalize();
    const State state = model.state();
    const Transform at = Transform::from_array(&state.body_q[7 * s.b]);
    EXPECT_LT((at.p - placed.p).norm(), 1e-12);
    EXPECT_LT(at.q.angularDistance(placed.q), 1e-12);
    if (type == JointType::Distance) {
      EXPECT_EQ(model.joint_limit_lower[model.joint_qd_start[1]], 0.5);
      EXPECT_EQ(model.joint_limit_upper[model.joint_qd_start[1]], 1.0);
    }
  }
}

TEST(MaximalJoints, BadInputIsNamed) {
  TwoBodies s;
  ModelBuilder& b = s.builder;
  EXPECT_NOVAPHY_ERROR(b.add_joint_distance(s.a, s.b, {}, -0.1, 1), "(Distance): min_distance must be finite and >= 0");
  EXPECT_NOVAPHY_ERROR(b.add_joint_distance(s.a, s.b, {}, 1, 0.5), "max_distance must be >= min_distance (1), got 0.5");
  EXPECT_NOVAPHY_ERROR(b.add_joint_distance(s.a, s.b, {}, 0, 1, -1), "(Distance): compliance must be finite and >= 0");
  EXPECT_NOVAPHY_ERROR(b.add_joint_cable(s.a, s.b, {}, 0, -2), "(Cable): bend_compliance must be finite and >= 0");
  EXPECT_NOVAPHY_ERROR(b.add_joint_d6(s.a, s.b, {}, {axis(Vec3::Zero())}, {}), "linear_axes[0] has zero length");
  EXPECT_NOVAPHY_ERROR(b.add_joint_d6(s.a, s.b, {}, {axis(Vec3::UnitX()), axis(Vec3::UnitX())}, {}),
                       "linear_axes[1] conflicts with an axis of its kind along the same direction");
  EXPECT_NOVAPHY_ERROR(b.add_joint_d6(s.a, s.b, {}, {axis(Vec3::UnitX())}, {axis(Vec3(1, 1, 0))}),
                       "angular_axes[0] is neither parallel nor perpendicular");
  EXPECT_NOVAPHY_ERROR(b.add_joint_d6(s.a, s.b, {}, {axis(Vec3::UnitX())}, {axis(-Vec3::UnitX())}),
                       "angular_axes[0] is the reverse of an axis given before");
  EXPECT_NOVAPHY_ERROR(
      b.add_joint_d6(s.a, s.b, {}, {axis(Vec3::UnitX()), axis(Vec3::UnitZ()), axis(Vec3::UnitY())}, {}),
      "the three axes are left-handed");
  EXPECT_NOVAPHY_ERROR(b.add_joint_d6(s.a, s.b, {}, {}, {axis(Vec3::UnitX(), 1, 0)}),
                       "limits must satisfy limit_lower <= limit_upper");
  EXPECT_NOVAPHY_ERROR(b.add_joint_d6(s.a, s.b, {}, {}, {}, -1), "(D6): linear_compliance must be finite and >= 0");
  EXPECT_NOVAPHY_ERROR(b.add_joint(JointType::D6, s.a, s.b, {}), "(D6): add it with add_joint_d6");
  EXPECT_EQ(b.joint_count(), 1);  // nothing added by a refused call
  // a direction given for both kinds is one axis: a D6 sliding along and turning about x
  EXPECT_NO_THROW(b.add_joint_d6(s.a, s.b, {}, {axis(Vec3::UnitX())}, {axis(Vec3::UnitX())}));
}

}  // namespace
}  // namespace novaphy
