#include "engine/model/builder.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/eval/eval.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

const Scalar kNaN = std::nan("");

JointOptions axis_z() {
  JointOptions options;
  options.dof.axis = Vec3(0, 0, 1);
  return options;
}

// the seed's pendulum example: a box on a revolute joint about z through its centre of mass
TEST(ModelBuilder, SeedPendulumMassMatrixIsAnalytic) {
  ModelBuilder builder;
  builder.add_ground_plane(0.0);
  const int body = builder.add_body(RigidBody::from_box(1.0, Vec3(0.1, 0.5, 0.1)));
  const int joint = builder.add_joint_revolute(-1, body, axis_z());
  builder.add_articulation({joint});
  const Model model = builder.finalize();
  EXPECT_EQ(model.articulation_count, 1);
  EXPECT_EQ(model.joint_dof_count, 1);
  const MatX H = eval_mass_matrix(model, model.state());
  EXPECT_NEAR(H(0, 0), 1.0 / 12 * (0.2 * 0.2 + 1.0 * 1.0), 1e-15);
}

// hinge at the top of a rod: I about the hinge = I_com + m d^2 (parallel axis), plus armature
TEST(ModelBuilder, OffsetPendulumMassMatrixIsAnalytic) {
  ModelBuilder builder;
  const int body = builder.add_body(RigidBody::from_box(2.0, Vec3(0.05, 0.5, 0.05)));
  JointOptions options = axis_z();
  options.child_xform.p = Vec3(0, 0.5, 0);
  options.dof.armature = 0.01;
  builder.add_joint_revolute(-1, body, options);
  const Model model = builder.finalize();
  State state = model.state();
  state.joint_q[0] = 0.7;
  const Scalar I_com = 2.0 / 12 * (0.1 * 0.1 + 1.0);
  EXPECT_NEAR(eval_mass_matrix(model, state)(0, 0), I_com + 2.0 * 0.25 + 0.01, 1e-14);
  // gravity torque: m g d sin(q) about the hinge
  EXPECT_NEAR(eval_bias_forces(model, state)[0], 2.0 * 9.81 * 0.5 * std::sin(0.7), 1e-13);
}

TEST(ModelBuilder, BodiesWithoutJointsBecomeFreeBodies) {
  ModelBuilder builder;
  Transform xform;
  xform.p = Vec3(1, 2, 3);
  xform.q = Quat(Eigen::AngleAxis<Scalar>(0.3, Vec3::UnitX()));
  builder.add_body(RigidBody::from_sphere(1, 0.1), xform);
  const Model model = builder.finalize();
  ASSERT_EQ(model.joint_count, 1);
  EXPECT_EQ(model.joint_type[0], static_cast<int>(JointType::Free));
  EXPECT_EQ(model.articulation_count, 1);
  const State state = model.state();
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(state.body_q[k], model.joint_q0[k], 1e-15);
  EXPECT_NEAR(state.body_q[1], 2, 1e-15);
  // falls freely: qdd = [0; g]
  const VecX qdd = eval_forward_dynamics(model, state, model.control());
  EXPECT_LT((qdd - (VecX(6) << 0, 0, 0, 0, -9.81, 0).finished()).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(ModelBuilder, JointsWithoutArticulationAreGroupedByTree) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int c = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_revolute(-1, a, axis_z());
  builder.add_joint_ball(a, b);
  builder.add_joint_prismatic(-1, c, axis_z());
  const Model model = builder.finalize();
  EXPECT_EQ(model.articulation_count, 2);
  EXPECT_EQ(model.articulation_start, (std::vector<int>{0, 2, 3}));
  EXPECT_EQ(model.joint_ancestor, (std::vector<int>{-1, 0, -1}));
  EXPECT_EQ(model.joint_q_start, (std::vector<int>{0, 1, 5, 6}));
  EXPECT_EQ(model.joint_qd_start, (std::vector<int>{0, 1, 4, 5}));
}

TEST(ModelBuilder, MotorsAddClampedForcesThroughTheirGear) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_ball(-1, a);
  const int hinge = builder.add_joint_revolute(a, b, axis_z());
  builder.add_motor(hinge, 40, -1, 1);
  builder.add_motor(hinge, 2, -10, 10, -3, 3, "weak");
  const Model model = builder.finalize();
  Control control = model.control();
  control.joint_f[3] = 0.5;
  control.actuator_ctrl = {1.5, 5.0};  // first clamped to 1 by its control range, second to 3 by its force range
  const VecX tau = eval_control_force(model, control);
  EXPECT_EQ(tau, (VecX(4) << 0, 0, 0, 0.5 + 40 * 1 + 2 * 3).finished());
  EXPECT_EQ(model.actuator_name[1], "weak");
}

TEST(ModelBuilderErrors, BadMotors) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int ball = builder.add_joint_ball(-1, a);
  EXPECT_NOVAPHY_ERROR(builder.add_motor(3), "actuator 0: joint index 3 out of range [0, 1)");
  EXPECT_NOVAPHY_ERROR(builder.add_motor(ball), "a motor drives a Revolute or Prismatic joint, joint 0 is Ball");
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int hinge = builder.add_joint_revolute(a, b);
  EXPECT_NOVAPHY_ERROR(builder.add_motor(hinge, 1, 2, 1), "control range must satisfy lower <= upper, got [2, 1]");
  EXPECT_NOVAPHY_ERROR(builder.add_motor(hinge, kNaN), "actuator 0: gear is not finite: nan");
  builder.add_motor(hinge);
  const Model model = builder.finalize();
  Control control = model.control();
  control.actuator_ctrl.clear();
  EXPECT_NOVAPHY_ERROR(eval_control_force(model, control), "actuator_ctrl has 0 entries, the model needs 1");
  control = model.control();
  control.actuator_ctrl[0] = kNaN;
  EXPECT_NOVAPHY_ERROR(eval_control_force(model, control), "actuator_ctrl[0] is not finite: nan");
}

// fuzz_builder finding: a model whose last joint has no coordinates (UB at finalize)
TEST(ModelBuilder, FixedJointsOnlyModelSteps) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_fixed(-1, a);
  builder.add_joint_fixed(a, b);
  const Model model = builder.finalize();
  EXPECT_EQ(model.joint_coord_count, 0);
  EXPECT_EQ(model.joint_dof_count, 0);
  State state = model.state();
  EXPECT_EQ(eval_forward_dynamics(model, state, model.control()).size(), 0);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstone solver(model);
  pipeline.collide(state, contacts);
  solver.step(state, state, model.control(), contacts, 0.01);
  EXPECT_EQ(state.body_q[7 + 3 + 3], 1);  // welded bodies stay put
}

// a pendulum swinging against a box on the ground, as one world
ModelBuilder pendulum_world() {
  ModelBuilder world;
  world.add_ground_plane();
  const int link = world.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  world.add_shape_box(link, Vec3(0.05, 0.25, 0.05));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.parent_xform.p = Vec3(0, 0.8, 0);
  options.child_xform.p = Vec3(-0.25, 0, 0);
  options.dof.limit_lower = -1.2;
  world.add_joint_revolute(-1, world.add_body(RigidBody::from_sphere(0.1, 0.01)), {});
  world.add_joint_revolute(-1, link, options);
  Transform x;
  x.p = Vec3(0.3, 0.1, 0);
  world.add_shape_box(world.add_body(RigidBody::from_box(1, Vec3::Constant(0.1)), x), Vec3::Constant(0.1));
  return world;
}

TEST(ModelBuilder, ReplicatedWorldsStepExactlyLikeOneWorldAlone) {
  ModelBuilder batch;
  batch.replicate(pendulum_world(), 5);  // all five on top of each other: worlds never collide
  const Model model = batch.finalize();
  const Model single = pendulum_world().finalize();
  EXPECT_EQ(model.world_count, 5);
  EXPECT_EQ(model.body_count, 5 * single.body_count);
  EXPECT_EQ(model.body_world[single.body_count], 1);
  EXPECT_EQ(model.shape_world[0], 0);  // each copy's ground plane belongs to its world
  auto run = [](const Model& m, int steps) {
    CollisionPipeline pipeline(m);
    Contacts contacts = pipeline.contacts();
    SolverFeatherstone solver(m);
    State state = m.state();
    const Control control = m.control();
    for (int k = 0; k < steps; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, control, contacts, 1.0 / 120);
    }
    return state;
  };
  const State alone = run(single, 240), together = run(model, 240);
  for (int w = 0; w < 5; ++w) {
    const std::vector<Scalar> q(together.joint_q.begin() + w * single.joint_coord_count,
                                together.joint_q.begin() + (w + 1) * single.joint_coord_count);
    EXPECT_EQ(q, alone.joint_q) << "world " << w;
  }
}

TEST(ModelBuilder, AddBuilderPlacesRootsFreeBodiesAndStaticShapes) {
  ModelBuilder batch;
  Transform x;
  x.p = Vec3(10, 0, 0);
  batch.add_builder(pendulum_world(), x, 3);
  batch.replicate(pendulum_world(), 2, Vec3(0, 0, 5));
  const Model model = batch.finalize();
  EXPECT_EQ(model.world_count, 6);
  const State state = model.state();
  EXPECT_EQ(model.body_world[0], 3);
  EXPECT_NEAR(state.body_q[7 * 2], 10.3, 1e-12);         // the free box, placed
  EXPECT_NEAR(model.shape_transform[0], 10, 1e-12);      // the static plane, placed
  EXPECT_NEAR(state.body_q[7 * (3 + 3) + 2], 5, 1e-12);  // the second copy's anchor body
  EXPECT_NOVAPHY_ERROR(batch.add_builder(batch), "add_builder: a builder cannot be added to itself");
  EXPECT_NOVAPHY_ERROR(batch.add_builder(pendulum_world(), {}, -2), "add_builder: world must be >= -1, got -2");
  EXPECT_NOVAPHY_ERROR(batch.replicate(pendulum_world(), 0), "replicate: world_count must be >= 1, got 0");
}

TEST(ModelBuilderErrors, ParentOutOfRangeOrNotYetDefined) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(7, a),
                       "joint 0 (Revolute): parent body index 7 out of range [-1, 2)");
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(-2, a), "parent body index -2 out of range");
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(-1, 5), "child body index 5 out of range [0, 2)");
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(b, a), "parent body 1 is not yet defined");
  EXPECT_NOVAPHY_ERROR(builder.add_joint_free(a, b), "parent body 0 is not yet defined");
  builder.add_joint_revolute(-1, a);
  EXPECT_NOVAPHY_ERROR(builder.add_joint_free(a, b), "a Free joint must be a root (parent -1), got parent 0");
}

TEST(ModelBuilderErrors, BodyClaimedByTwoJoints) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_revolute(-1, a);
  EXPECT_NOVAPHY_ERROR(builder.add_joint_prismatic(-1, a),
                       "joint 1 (Prismatic): body 0 is already the child of joint 0");
}

TEST(ModelBuilderErrors, BadMass) {
  ModelBuilder builder;
  RigidBody body;
  body.mass = 0;
  EXPECT_NOVAPHY_ERROR(builder.add_body(body, {}, "arm"), "body 0 ('arm'): mass must be > 0, got 0");
  body.mass = -1;
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: mass must be > 0, got -1");
  body.mass = kNaN;
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: mass is not finite: nan");
  EXPECT_EQ(builder.body_count(), 0);
}

TEST(ModelBuilderErrors, BadInertia) {
  ModelBuilder builder;
  RigidBody body;
  body.inertia(0, 1) = 0.5;
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: inertia is not symmetric");
  body.inertia = Vec3(1, 1, -1).asDiagonal();
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: inertia is not positive definite");
  body.inertia = Vec3(1, 1, 3).asDiagonal();
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: inertia violates the triangle inequality");
  body.inertia = Mat3::Identity();
  body.inertia(2, 2) = kNaN;
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: inertia(2, 2) is not finite: nan");
  body.inertia = Mat3::Identity();
  body.com = Vec3(0, kNaN, 0);
  EXPECT_NOVAPHY_ERROR(builder.add_body(body), "body 0: com[1] is not finite: nan");
}

TEST(ModelBuilderErrors, BadAxisTransformsAndLimits) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  JointOptions options;
  options.dof.axis = Vec3::Zero();
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(-1, a, options), "joint 0 (Revolute): axis has zero length");
  options.dof.axis = Vec3(0, kNaN, 1);
  EXPECT_NOVAPHY_ERROR(builder.add_joint_prismatic(-1, a, options), "joint 0 (Prismatic): axis[1] is not finite: nan");
  options = {};
  options.parent_xform.p = Vec3(kNaN, 0, 0);
  EXPECT_NOVAPHY_ERROR(builder.add_joint_ball(-1, a, options), "joint 0 (Ball): parent_xform[0] is not finite: nan");
  options = {};
  options.child_xform.q = Quat(kNaN, 0, 0, 0);
  EXPECT_NOVAPHY_ERROR(builder.add_joint_ball(-1, a, options), "joint 0 (Ball): child_xform rotation[3] is not finite");
  options = {};
  options.child_xform.q = Quat(0, 0, 0, 0);
  EXPECT_NOVAPHY_ERROR(builder.add_joint_ball(-1, a, options), "child_xform rotation quaternion has zero length");
  options = {};
  options.dof.limit_lower = 1;
  options.dof.limit_upper = -1;
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(-1, a, options), "limits must satisfy limit_lower <= limit_upper");
  options = {};
  options.dof.damping = -0.1;
  EXPECT_NOVAPHY_ERROR(builder.add_joint_revolute(-1, a, options), "damping must be finite and >= 0, got -0.1");
  Transform bad;
  bad.p = Vec3(0, 0, kNaN);
  EXPECT_NOVAPHY_ERROR(builder.add_body(RigidBody(), bad), "body 1: xform[2] is not finite: nan");
  EXPECT_EQ(builder.joint_count(), 0);
}

TEST(ModelBuilderErrors, BadArticulationsAndShapes) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int ja = builder.add_joint_revolute(-1, a);
  const int jb = builder.add_joint_revolute(a, b);
  EXPECT_NOVAPHY_ERROR(builder.add_articulation({}), "articulation 0: no joints");
  EXPECT_NOVAPHY_ERROR(builder.add_articulation({ja, 9}), "articulation 0: joint index 9 out of range [0, 2)");
  EXPECT_NOVAPHY_ERROR(builder.add_articulation({jb}), "joint 1 hangs from body 0 which is not in this articulation");
  builder.add_articulation({ja, jb});
  EXPECT_NOVAPHY_ERROR(builder.add_articulation({jb}), "joint 1 already belongs to articulation 0");
  EXPECT_NOVAPHY_ERROR(builder.add_shape_sphere(3, 0.1), "shape 0 (Sphere): body index 3 out of range [-1, 2)");
  EXPECT_NOVAPHY_ERROR(builder.add_shape_box(a, Vec3(0.1, 0, 0.1)),
                       "shape 0 (Box): size must be finite and > 0, got 0");
  ShapeOptions bouncy;
  bouncy.restitution = 2;
  EXPECT_NOVAPHY_ERROR(builder.add_shape_sphere(a, 0.1, bouncy), "restitution must be in [0, 1], got 2");
  EXPECT_NOVAPHY_ERROR(builder.add_plane(Vec3::Zero(), 0), "plane: normal has zero length");
}

TEST(ModelBuilderErrors, InterleavedArticulationsAtFinalize) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.1));
  const int c = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_revolute(-1, a);
  builder.add_joint_revolute(-1, b);  // a second tree starts
  builder.add_joint_revolute(a, c);   // ... and the first one goes on after it
  EXPECT_NOVAPHY_ERROR(builder.finalize(), "joint 2: its articulation's joints are not contiguous");
}

TEST(ModelBuilderErrors, MassMatrixNotPositiveDefiniteNamesTheJoint) {
  ModelBuilder builder;
  JointOptions options;
  options.name = "wrist";
  builder.add_joint_revolute(-1, builder.add_body(RigidBody::from_sphere(1, 0.1)), options);
  Model model = builder.finalize();
  model.body_mass[0] = 0;  // a massless leaf, as no builder call allows
  std::fill(model.body_inertia.begin(), model.body_inertia.end(), 0);
  for (const auto method : {ForwardDynamicsMethod::Crba, ForwardDynamicsMethod::Aba})
    EXPECT_NOVAPHY_ERROR(eval_forward_dynamics(model, model.state(), model.control(), method),
                         "articulation 0: mass matrix is not positive definite at dof 0 (joint 0 'wrist'");
}

TEST(ModelBuilderErrors, StateFromAnotherModelAndNonFiniteCoordinates) {
  ModelBuilder one, two;
  one.add_body(RigidBody::from_sphere(1, 0.1));
  two.add_joint_revolute(-1, two.add_body(RigidBody::from_sphere(1, 0.1)));
  const Model model_one = one.finalize(), model_two = two.finalize();
  State state = model_two.state();
  EXPECT_NOVAPHY_ERROR(eval_fk(model_one, state), "joint_q has 1 entries, the model needs 7");
  State nan_state = model_one.state();
  nan_state.joint_qd[4] = kNaN;
  EXPECT_NOVAPHY_ERROR(eval_mass_matrix(model_one, nan_state), "joint_qd[4] is not finite: nan");
  EXPECT_NOVAPHY_ERROR(eval_inverse_dynamics(model_one, model_one.state(), VecX::Zero(2)),
                       "qdd has 2 entries, the model has 6 dofs");
}

}  // namespace
}  // namespace novaphy
