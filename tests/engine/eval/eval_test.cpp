// ForwardDynamics (engine/eval/eval.h): the step's batched kernels made once for a model, evaluated again and
// again, against the reference kernels' CRBA + Cholesky (eval_forward_dynamics) on MuJoCo's humanoid; and
// set_invweight0's sharing of weights between replicas.
#include "engine/eval/eval.h"

#include <gtest/gtest.h>

#include "engine/import/mjcf_import.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

Model humanoid(Precision precision, int worlds) {
  ModelBuilder robot;
  robot.add_mjcf(NOVAPHY_HUMANOID_XML);
  ModelBuilder batch(robot.gravity());
  batch.set_precision(precision);
  batch.replicate(robot, worlds);
  return batch.finalize();
}

// a state of every world its own: coordinates, velocities, forces and applied wrenches
void random_state(const Model& model, State& state, Control& control) {
  for (size_t k = 0; k < state.joint_qd.size(); ++k) state.joint_qd[k] = std::sin(1.7 * k) * 2;
  for (size_t k = 0; k < state.joint_q.size(); ++k) state.joint_q[k] += 0.3 * std::cos(0.9 * k);
  for (int j = 0; j < model.joint_count; ++j)
    if (model.joint_type[j] == static_cast<int>(JointType::Free)) {
      Scalar* quat = &state.joint_q[model.joint_q_start[j] + 3];
      Eigen::Map<Quat>(quat).normalize();
    }
  for (size_t k = 0; k < control.joint_f.size(); ++k) control.joint_f[k] = std::cos(0.4 * k);
  for (size_t k = 0; k < state.body_f.size(); ++k) state.body_f[k] = 0.1 * std::sin(0.3 * k);
}

TEST(ForwardDynamics, MatchesTheReferenceKernelsAndRepeatsItsBits) {
  for (const Precision precision : {Precision::Float64, Precision::Float32}) {
    const Model model = humanoid(precision, 3);
    State state = model.state();
    Control control = model.control();
    random_state(model, state, control);
    const VecX expected = eval_forward_dynamics(model, state, control);
    ForwardDynamics dynamics(model);
    VecX first(model.joint_dof_count), again(model.joint_dof_count);
    dynamics.evaluate(state, control, first.data());
    dynamics.evaluate(state, control, again.data());
    EXPECT_EQ(first, again);
    const Scalar scale = expected.cwiseAbs().maxCoeff();
    EXPECT_LT((first - expected).cwiseAbs().maxCoeff() / scale, precision == Precision::Float64 ? 1e-12 : 1e-4);
    // another state through the same object: its own accelerations
    state.joint_qd[0] += 1;
    dynamics.evaluate(state, control, again.data());
    EXPECT_LT((again - eval_forward_dynamics(model, state, control)).cwiseAbs().maxCoeff() / scale,
              precision == Precision::Float64 ? 1e-12 : 1e-4);
  }
}

TEST(ForwardDynamics, ChecksItsArguments) {
  const Model model = humanoid(Precision::Float64, 1);
  ForwardDynamics dynamics(model);
  State state = model.state();
  Control control = model.control();
  VecX qdd(model.joint_dof_count);
  state.joint_qd[4] = std::nan("");
  EXPECT_NOVAPHY_ERROR(dynamics.evaluate(state, control, qdd.data()), "joint_qd[4] is not finite");
  state.joint_qd[4] = 0;
  control.joint_f.resize(3);
  EXPECT_NOVAPHY_ERROR(dynamics.evaluate(state, control, qdd.data()), "joint_f");
}

// a branching robot: a Free or hinged base, a Ball shoulder carrying two hinged arms, armature on every dof, the
// second arm of mass `tip`; its dofs' limits of solref `limit_solref`
ModelBuilder branching_robot(bool floating, Scalar tip, const std::array<Scalar, 2>& limit_solref = {0, 0}) {
  ModelBuilder builder;
  JointOptions options;
  options.dof.armature = 0.02;
  options.dof.limit_solref = limit_solref;
  options.dof.axis = Vec3(0, 0.6, 0.8);
  const int base = builder.add_body(RigidBody::from_box(3, Vec3(0.2, 0.1, 0.1)), Transform::identity(), "base");
  floating ? builder.add_joint_free(-1, base, options) : builder.add_joint_revolute(-1, base, options);
  const int shoulder = builder.add_body(RigidBody::from_sphere(0.5, 0.05));
  options.parent_xform.p = Vec3(0.2, 0, 0);
  builder.add_joint_ball(base, shoulder, options);
  for (int k = 0; k < 2; ++k) {
    RigidBody arm = RigidBody::from_capsule(0.4, 0.03, 0.1);
    arm.com = Vec3(0, 0.1, 0.02);
    if (k == 1) arm.mass = tip;  // (the mass alone: its inertia about the centre of mass stays)
    options.parent_xform.q = Quat(Eigen::AngleAxis<Scalar>(0.4 + 0.3 * k, Vec3::UnitX()));
    builder.add_joint_revolute(shoulder, builder.add_body(arm), options);
  }
  return builder;
}

// replicas (replicate, add_builder elsewhere) get their original's weights, bit for bit, and an articulation that
// differs in one body's mass alone its own: each world as its robot finalized alone
TEST(BodyInvweight0, ReplicasGetTheirOriginalsWeightsAndOthersTheirOwn) {
  for (const bool floating : {false, true}) {
    const Model lone = branching_robot(floating, 0.3).finalize();
    const Model other = branching_robot(floating, 0.31).finalize();
    ModelBuilder scene;
    scene.replicate(branching_robot(floating, 0.3), 3, Vec3(2, 0, 0));
    Transform place;
    place.p = Vec3(0, 5, 1);
    if (!floating) place.q = Quat(Eigen::AngleAxis<Scalar>(0.7, Vec3(1, 2, 3).normalized()));
    scene.add_builder(branching_robot(floating, 0.31), place);
    scene.add_builder(branching_robot(floating, 0.3), place);
    const Model model = scene.finalize();
    const int n = 2 * lone.body_count;
    ASSERT_EQ(model.body_invweight0.size(), static_cast<size_t>(5 * n));
    for (int w = 0; w < 5; ++w) {
      const Model& expected = w == 3 ? other : lone;
      for (int k = 0; k < n; ++k)
        EXPECT_EQ(model.body_invweight0[w * n + k], expected.body_invweight0[k])
            << (floating ? "floating" : "fixed") << ", world " << w << ", weight " << k;
    }
    EXPECT_NE(other.body_invweight0[n - 2], lone.body_invweight0[n - 2]);  // (the second arm's translation weight)
    EXPECT_GT(lone.body_invweight0[n - 2], 0);
  }
}

// where a soft row weighs them: a dof's invweight0 is M^-1's diagonal at joint_q0 (averaged over a Ball's dofs and a
// Free joint's rotations and translations, as MuJoCo's dof_invweight0), a tendon's J M^-1 J^T; a replica gets its
// original's; without a soft row they are 0
TEST(JointInvweight0, IsTheInverseMassMatrixsDiagonalAndATendonsJMinvJt) {
  for (const bool floating : {false, true}) {
    ModelBuilder robot = branching_robot(floating, 0.3, {0.02, 1});
    const int arms[2] = {robot.joint_count() - 2, robot.joint_count() - 1};
    robot.add_tendon({arms[0], arms[1]}, {1.0, -0.5});
    ModelBuilder scene;
    scene.replicate(robot, 2, Vec3(2, 0, 0));
    const Model model = scene.finalize();
    const MatX Minv = eval_mass_matrix(model, model.state()).inverse();
    const int n = model.joint_dof_count / 2;
    VecX expected = Minv.diagonal().head(n);
    const int ball = floating ? 6 : 1;  // (the Free joint's dofs: its rotations, then its translations)
    auto average = [&](int from) { expected.segment(from, 3).setConstant(expected.segment(from, 3).mean()); };
    if (floating) average(0), average(3);
    average(ball);
    for (int k = 0; k < n; ++k) {
      EXPECT_NEAR(model.joint_invweight0[k], expected[k], 1e-12 * expected[k]) << "dof " << k;
      EXPECT_EQ(model.joint_invweight0[n + k], model.joint_invweight0[k]) << "replica's dof " << k;
    }
    VecX J = VecX::Zero(2 * n);
    J[n - 2] = 1, J[n - 1] = -0.5;
    EXPECT_NEAR(model.tendon_invweight0[0], J.dot(Minv * J), 1e-12 * J.dot(Minv * J));
    J.head(n).swap(J.tail(n));
    EXPECT_NEAR(model.tendon_invweight0[1], J.dot(Minv * J), 1e-12 * J.dot(Minv * J));
    const Model hard = branching_robot(floating, 0.3).finalize();
    EXPECT_TRUE(
        std::all_of(hard.joint_invweight0.begin(), hard.joint_invweight0.end(), [](Scalar w) { return w == 0; }));
  }
}

}  // namespace
}  // namespace novaphy
