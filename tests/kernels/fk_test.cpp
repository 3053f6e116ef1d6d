#include "kernels/fk.h"

#include <gtest/gtest.h>

#include "engine/eval/eval.h"
#include "test_support.h"

namespace novaphy {
namespace {

Quat exp_quat(const Vec3& rotation) {
  const Scalar angle = rotation.norm();
  return angle == 0 ? Quat::Identity() : Quat(Eigen::AngleAxis<Scalar>(angle, rotation / angle));
}

// q advanced by h along qd with DESIGN.md's velocity conventions
std::vector<Scalar> advance(const Model& model, const State& state, Scalar h) {
  std::vector<Scalar> q = state.joint_q;
  for (int j = 0; j < model.joint_count; ++j) {
    Scalar* x = q.data() + model.joint_q_start[j];  // past the end for a Fixed joint
    const Scalar* v = state.joint_qd.data() + model.joint_qd_start[j];
    switch (static_cast<JointType>(model.joint_type[j])) {
      case JointType::Revolute:
      case JointType::Prismatic: x[0] += h * v[0]; break;
      case JointType::Ball: {  // angular velocity in the child joint frame
        const Quat r = joint_quat(x) * exp_quat(h * Vec3(v[0], v[1], v[2]));
        Eigen::Map<Eigen::Vector4d>{x} = r.coeffs();
        break;
      }
      case JointType::Free:
      case JointType::Distance:
      case JointType::D6:
      case JointType::Cable: {  // [w; v] in the parent frame
        for (int k = 0; k < 3; ++k) x[k] += h * v[3 + k];
        const Quat r = exp_quat(h * Vec3(v[0], v[1], v[2])) * joint_quat(x + 3);
        Eigen::Map<Eigen::Vector4d>{x + 3} = r.coeffs();
        break;
      }
      case JointType::Fixed: break;
    }
  }
  return q;
}

TEST(ForwardKinematics, PendulumPoseIsAnalytic) {
  ModelBuilder builder;
  const int body = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.5, 0.1)));
  JointOptions options;
  options.parent_xform.p = Vec3(0, 2, 0);
  options.child_xform.p = Vec3(0, 0.5, 0);  // the joint sits 0.5 above the link origin
  options.dof.axis = Vec3(0, 0, 1);
  builder.add_joint_revolute(-1, body, options);
  const Model model = builder.finalize();
  State state = model.state();
  state.joint_q[0] = M_PI / 2;
  state.joint_qd[0] = 3;
  eval_fk(model, state);
  // the link origin hangs 0.5 from the hinge, swung to +x
  EXPECT_NEAR(state.body_q[0], 0.5, 1e-15);
  EXPECT_NEAR(state.body_q[1], 2.0, 1e-15);
  EXPECT_NEAR(state.body_q[2], 0.0, 1e-15);
  EXPECT_NEAR(state.body_q[5], std::sin(M_PI / 4), 1e-15);  // qz
  EXPECT_NEAR(state.body_q[6], std::cos(M_PI / 4), 1e-15);  // qw
  // body_qd = [v_com; w]: the centre of mass (link origin) moves at 3 * 0.5 along +y
  const Vec6 expected = (Vec6() << 0, 1.5, 0, 0, 0, 3).finished();
  EXPECT_LT((Eigen::Map<const Vec6>(state.body_qd.data()) - expected).cwiseAbs().maxCoeff(), 1e-14);
}

// body_qd = [v_com; w] in the world equals the finite difference of body_q along qd
TEST(ForwardKinematics, BodyVelocitiesMatchFiniteDifferences) {
  std::mt19937 rng(6);
  const Scalar h = 1e-6;
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 8);
    State state = model.state();
    test::randomize_state(model, state, rng, false);
    eval_fk(model, state);

    State plus = state, minus = state;
    plus.joint_q = advance(model, state, h);
    minus.joint_q = advance(model, state, -h);
    eval_fk(model, plus);
    eval_fk(model, minus);
    for (int b = 0; b < model.body_count; ++b) {
      const Transform Tp = Transform::from_array(&plus.body_q[7 * b]);
      const Transform Tm = Transform::from_array(&minus.body_q[7 * b]);
      const Vec3 com = Eigen::Map<const Vec3>(&model.body_com[3 * b]);
      const Vec3 v_fd = (Tp.apply(com) - Tm.apply(com)) / (2 * h);
      const Eigen::AngleAxis<Scalar> dR(Tp.q * Tm.q.conjugate());
      const Vec3 w_fd = dR.axis() * dR.angle() / (2 * h);
      const Eigen::Map<const Vec6> qd(&state.body_qd[6 * b]);
      EXPECT_LT((qd.head<3>() - v_fd).norm(), 1e-6 * std::max<Scalar>(1, v_fd.norm())) << "trial " << trial;
      EXPECT_LT((qd.tail<3>() - w_fd).norm(), 1e-6 * std::max<Scalar>(1, w_fd.norm())) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace novaphy
