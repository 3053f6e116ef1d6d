#include "engine/eval/articulation_functions.h"

#include <gtest/gtest.h>

#include "engine/eval/eval.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

const Scalar kNaN = std::nan("");

// a two-link planar arm: revolute joints about z, links along -y
struct TwoLinkArm {
  std::vector<Joint> joints;
  std::vector<RigidBody> bodies;
  TwoLinkArm() {
    Joint shoulder;
    shoulder.axis = Vec3(0, 0, 1);
    Joint elbow = shoulder;
    elbow.parent = 0;
    elbow.parent_to_joint.p = Vec3(0, -1, 0);
    joints = {shoulder, elbow};
    RigidBody link;
    link.mass = 1;
    link.com = Vec3(0, -0.5, 0);
    link.inertia = Vec3(0.1, 0.01, 0.1).asDiagonal();
    bodies = {link, link};
  }
};

TEST(ArticulationFunctions, ForwardKinematicsOfTwoLinkArm) {
  const TwoLinkArm arm;
  const auto X = forward_kinematics(arm.joints, (VecX(2) << M_PI / 2, M_PI / 2).finished());
  ASSERT_EQ(X.rows(), 2);
  // shoulder at the origin, elbow one unit along +x after a quarter turn
  EXPECT_NEAR(X(1, 0), 1, 1e-15);
  EXPECT_NEAR(X(1, 1), 0, 1e-15);
  EXPECT_NEAR(std::abs(X(1, 5)), 1, 1e-15);  // half a turn about z in total
}

TEST(ArticulationFunctions, MassMatrixOfTwoLinkArmIsAnalytic) {
  const TwoLinkArm arm;
  const Scalar q2 = 0.4;
  const MatX H = mass_matrix_crba(arm.joints, arm.bodies, (VecX(2) << 0.3, q2).finished());
  // planar two-link arm: m = 1, l = 1, c = 0.5, I = 0.1 about each centre of mass
  const Scalar h22 = 0.1 + 0.25;
  const Scalar h12 = h22 + 0.5 * std::cos(q2);
  const Scalar h11 = 2 * h22 + 1 + std::cos(q2);
  EXPECT_NEAR(H(0, 0), h11, 1e-14);
  EXPECT_NEAR(H(0, 1), h12, 1e-14);
  EXPECT_NEAR(H(1, 1), h22, 1e-14);
}

TEST(ArticulationFunctions, InverseDynamicsInvertsForwardDynamics) {
  const TwoLinkArm arm;
  const VecX q = (VecX(2) << 0.3, -1.1).finished(), qd = (VecX(2) << 0.5, 2.0).finished();
  const VecX tau = (VecX(2) << 1.5, -0.25).finished();
  const Vec3 g(0, -9.81, 0);
  const VecX qdd = forward_dynamics(arm.joints, arm.bodies, q, qd, tau, g);
  EXPECT_LT((inverse_dynamics(arm.joints, arm.bodies, q, qd, qdd, g) - tau).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ArticulationFunctions, ForwardDynamicsOfAnotherArmInBetweenIsItsOwn) {
  // the free function keeps the last articulation's kernels: asking about another in between, or about the same
  // joints with other bodies, gives each its own accelerations (the reference kernels' CRBA the oracle)
  const TwoLinkArm arm;
  TwoLinkArm heavier, longer;
  heavier.bodies[1].mass = 3;
  longer.joints[1].parent_to_joint.p = Vec3(0, -1.5, 0);
  const VecX q = (VecX(2) << 0.3, -1.1).finished(), qd = (VecX(2) << 0.5, 2.0).finished();
  const VecX tau = (VecX(2) << 1.5, -0.25).finished();
  const Vec3 g(0, -9.81, 0);
  for (const TwoLinkArm* a : std::vector<const TwoLinkArm*>{&arm, &heavier, &arm, &longer, &longer, &arm}) {
    const Model model = articulation_model(a->joints, a->bodies, g);
    State state = model.state();
    Control control = model.control();
    for (int k = 0; k < 2; ++k) state.joint_q[k] = q[k], state.joint_qd[k] = qd[k], control.joint_f[k] = tau[k];
    const VecX expected = eval_forward_dynamics(model, state, control);
    EXPECT_LT((forward_dynamics(a->joints, a->bodies, q, qd, tau, g) - expected).cwiseAbs().maxCoeff(), 1e-12);
  }
  // a call that fails leaves the next ones right
  const VecX before = forward_dynamics(arm.joints, arm.bodies, q, qd, tau, g);
  EXPECT_NOVAPHY_ERROR(forward_dynamics(arm.joints, arm.bodies, q, qd, tau, Vec3(0, kNaN, 0)),
                       "gravity[1] is not finite: nan");
  EXPECT_EQ(forward_dynamics(arm.joints, arm.bodies, q, qd, tau, g), before);
}

TEST(ArticulationFunctionsErrors, WrongLengthsAndNonFiniteValues) {
  const TwoLinkArm arm;
  const VecX two = VecX::Zero(2);
  EXPECT_NOVAPHY_ERROR(forward_kinematics(arm.joints, VecX::Zero(3)), "q has 3 entries, the joints need 2");
  EXPECT_NOVAPHY_ERROR(inverse_dynamics(arm.joints, arm.bodies, two, VecX::Zero(1), two, Vec3::Zero()),
                       "qd has 1 entries, the joints need 2");
  EXPECT_NOVAPHY_ERROR(inverse_dynamics(arm.joints, arm.bodies, two, two, VecX::Zero(5), Vec3::Zero()),
                       "qdd has 5 entries, the model has 2 dofs");
  EXPECT_NOVAPHY_ERROR(forward_dynamics(arm.joints, arm.bodies, two, two, VecX::Zero(1), Vec3::Zero()),
                       "tau has 1 entries, the joints need 2");
  EXPECT_NOVAPHY_ERROR(
      forward_dynamics(arm.joints, arm.bodies, (VecX(2) << 0, kNaN).finished(), two, two, Vec3::Zero()),
      "q[1] is not finite: nan");
  EXPECT_NOVAPHY_ERROR(mass_matrix_crba(arm.joints, {arm.bodies[0]}, two), "joints and bodies differ in length");
  EXPECT_NOVAPHY_ERROR(inverse_dynamics(arm.joints, arm.bodies, two, two, two, Vec3(0, kNaN, 0)),
                       "gravity[1] is not finite: nan");
  std::vector<Joint> forward_reference = arm.joints;
  forward_reference[0].parent = 1;
  EXPECT_NOVAPHY_ERROR(mass_matrix_crba(forward_reference, arm.bodies, two),
                       "joint 0: parent link 1 is not yet defined");
}

}  // namespace
}  // namespace novaphy
