#include "engine/solver/solver_featherstone.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "solver_test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

using namespace solver_test;

TEST(SolverFeatherstone, BoxRestsWithinSlopWithoutDrift) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int box = add_box(builder, Vec3(0, 0.2, 0));
  Scene scene(builder);
  Scalar worst = 0;
  scene.run(10, kDt, [&] { worst = std::max(worst, std::abs(scene.position(box).y() - 0.2)); });
  EXPECT_LE(worst, scene.solver.settings.linear_slop);
  EXPECT_LT(std::abs(scene.position(box).x()) + std::abs(scene.position(box).z()), 1e-6);  // a micrometre in 10 s
  EXPECT_LT(scene.velocity(box).norm(), 1e-6);
  EXPECT_EQ(scene.contacts.contact_count, 4);
}

TEST(SolverFeatherstone, FiveBoxTowerStandsTenSeconds) {
  ModelBuilder builder;
  builder.add_ground_plane();
  std::vector<int> boxes;
  for (int k = 0; k < 5; ++k) boxes.push_back(add_box(builder, Vec3(0, 0.2 + 0.4 * k, 0)));
  Scene scene(builder);
  scene.run(10);
  for (int k = 0; k < 5; ++k) {
    const Vec3 p = scene.position(boxes[k]);
    EXPECT_LT((p - Vec3(0, 0.2 + 0.4 * k, 0)).norm(), 0.01) << "box " << k;
  }
}

// a box released on a slope of 30 degrees with mu = 0.2 slides with a = g (sin - mu cos)
TEST(SolverFeatherstone, BoxOnSlopeSlidesAtCoulombAcceleration) {
  const Scalar angle = M_PI / 6, mu = 0.2;
  const Quat tilt(Eigen::AngleAxis<Scalar>(angle, Vec3::UnitZ()));
  const Vec3 n = tilt * Vec3::UnitY(), down_slope = tilt * Vec3(-1, 0, 0);
  ModelBuilder builder;
  builder.add_plane(n, 0, material(mu));
  const int box = builder.add_body(RigidBody::from_box(1, Vec3::Constant(0.2)), Transform{0.2 * n, tilt});
  builder.add_shape_box(box, Vec3::Constant(0.2), material(mu));
  Scene scene(builder, no_damping());
  scene.run(0.5);
  const Scalar v0 = scene.velocity(box).dot(down_slope);
  scene.run(1.0);
  const Scalar measured = (scene.velocity(box).dot(down_slope) - v0) / 1.0;
  const Scalar expected = 9.81 * (std::sin(angle) - mu * std::cos(angle));
  EXPECT_NEAR(measured, expected, 0.05 * expected);
}

TEST(SolverFeatherstone, BoxOnSlopeWithEnoughFrictionStays) {
  const Scalar angle = M_PI / 6, mu = 0.8;
  const Quat tilt(Eigen::AngleAxis<Scalar>(angle, Vec3::UnitZ()));
  const Vec3 n = tilt * Vec3::UnitY();
  ModelBuilder builder;
  builder.add_plane(n, 0, material(mu));
  const int box = builder.add_body(RigidBody::from_box(1, Vec3::Constant(0.2)), Transform{0.2 * n, tilt});
  builder.add_shape_box(box, Vec3::Constant(0.2), material(mu));
  Scene scene(builder);
  scene.run(3);
  EXPECT_LT((scene.position(box) - 0.2 * n).norm(), 0.005);
}

// a ball dropped from 1 m onto the ground bounces to e^2 of its height
TEST(SolverFeatherstone, BounceHeightFollowsRestitution) {
  for (const Scalar e : {0.5, 0.8}) {
    ModelBuilder builder;
    builder.add_ground_plane(0, material(0.5, e));
    const int ball = builder.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0, 1.1, 0)});
    builder.add_shape_sphere(ball, 0.1, material(0.5, e));
    SolverFeatherstoneSettings settings = no_damping();
    settings.restitution_threshold = 0.05;
    Scene scene(builder, settings);
    Scalar peak = 0;
    bool bounced = false;
    scene.run(0.45 + 2 * e, 1.0 / 1000, [&] {
      if (scene.velocity(ball).y() > 0) bounced = true;
      if (bounced) peak = std::max(peak, scene.position(ball).y() - 0.1);
    });
    EXPECT_NEAR(peak, e * e * 1.0, 0.05 * e * e) << "restitution " << e;
  }
}

// a link driven by a stiff PD drive (implicit, so kp = 1e4 is stable at dt = 1/60) reaches its target
TEST(SolverFeatherstone, PdArmReachesTarget) {
  ModelBuilder builder;
  const int arm = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(0, 0.25, 0);  // hinge at the top of the link
  const int joint = builder.add_joint_revolute(-1, arm, options);
  Scene scene(builder);
  scene.control.joint_target_pos[joint] = 1.0;
  scene.control.joint_target_ke[joint] = 1e4;
  scene.control.joint_target_kd[joint] = 200;
  scene.run(3, 1.0 / 60);
  EXPECT_NEAR(scene.state.joint_q[0], 1.0, 0.01);
  EXPECT_LT(std::abs(scene.state.joint_qd[0]), 1e-3);
}

TEST(SolverFeatherstone, LimitsHoldAJointInsideItsRange) {
  ModelBuilder builder;
  const int arm = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.25, 0, 0);  // horizontal link: gravity swings it down
  options.dof.limit_lower = -0.5;
  options.dof.limit_upper = 0.5;
  builder.add_joint_revolute(-1, arm, options);
  Scene scene(builder);
  Scalar lowest = 0;
  scene.run(3, kDt, [&] { lowest = std::min(lowest, scene.state.joint_q[0]); });
  EXPECT_GE(lowest, -0.5 - 0.02);
  EXPECT_NEAR(scene.state.joint_q[0], -0.5, scene.solver.settings.linear_slop + 1e-6);
}

// the same MJCF stepped by MuJoCo (its own soft contacts) and by NovaPhy comes to rest at the same height
Scalar mujoco_rest_height(const std::string& path, const char* body, Scalar seconds) {
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(path), mj_deleteModel);
  const std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m.get()), mj_deleteData);
  const int steps = static_cast<int>(std::lround(seconds / m->opt.timestep));
  for (int k = 0; k < steps; ++k) mj_step(m.get(), d.get());
  return d->xpos[3 * mj_name2id(m.get(), mjOBJ_BODY, body) + 2];
}

Scalar novaphy_rest_height(const std::string& path, const char* body, Scalar seconds, Scalar dt) {
  ModelBuilder builder;
  const MujocoImport import = import_mjcf(builder, path);
  Scene scene(builder);
  scene.run(seconds, dt);
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(path), mj_deleteModel);
  return scene.position(import.body_map[mj_name2id(m.get(), mjOBJ_BODY, body)]).z();
}

TEST(SolverFeatherstone, BoxDropRestsWhereMujocoRests) {
  const std::string path = NOVAPHY_SCENE_DIR "/box_drop.xml";
  const Scalar mujoco = mujoco_rest_height(path, "box", 3), novaphy = novaphy_rest_height(path, "box", 3, 0.005);
  EXPECT_NEAR(novaphy, mujoco, 0.01);
  EXPECT_NEAR(novaphy, 0.1, 0.01);  // on its smallest face
}

TEST(SolverFeatherstone, QuadrupedSettlesWhereMujocoSettles) {
  const std::string path = NOVAPHY_SCENE_DIR "/quadruped.xml";
  const Scalar mujoco = mujoco_rest_height(path, "torso", 4), novaphy = novaphy_rest_height(path, "torso", 4, 0.005);
  EXPECT_NEAR(novaphy, mujoco, 0.01);
  EXPECT_GT(novaphy, 0.3);  // standing on its feet
}

// fuzz_builder finding: a contact with a body whose articulation has no dofs (UB in the row setup)
TEST(SolverFeatherstone, WeldedBodiesActAsStatic) {
  ModelBuilder builder;
  const int table = builder.add_body(RigidBody::from_box(1, Vec3(1, 0.1, 1)));
  builder.add_shape_box(table, Vec3(1, 0.1, 1));
  builder.add_joint_fixed(-1, table);
  const int ball = builder.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0, 0.5, 0)});
  builder.add_shape_sphere(ball, 0.1);
  Scene scene(builder);
  scene.run(2);
  EXPECT_NEAR(scene.position(ball).y(), 0.2, scene.solver.settings.linear_slop + 1e-6);
  EXPECT_EQ(scene.position(table), Vec3::Zero());
}

TEST(SolverFeatherstone, StateInMayBeStateOut) {
  ModelBuilder builder;
  builder.add_ground_plane();
  add_box(builder, Vec3(0, 0.5, 0));
  Scene a(builder), b(builder);
  State out = b.state;
  for (int k = 0; k < 120; ++k) {
    a.pipeline.collide(a.state, a.contacts);
    a.solver.step(a.state, a.state, a.control, a.contacts, kDt);
    b.pipeline.collide(b.state, b.contacts);
    b.solver.step(b.state, out, b.control, b.contacts, kDt);
    b.state = out;
  }
  EXPECT_EQ(a.state.joint_q, b.state.joint_q);
  EXPECT_EQ(a.state.body_q, b.state.body_q);
}

// the step sums the control's forces dof by dof on its threads: joint_f, then each motor on the dof
// (two on one hinge here) clamped and geared. One step from rest, in every world of a batch, gives the
// velocity dt * qdd of eval_forward_dynamics, which adds them motor by motor
TEST(SolverFeatherstone, MotorsDriveEveryWorldAsForwardDynamicsSays) {
  ModelBuilder robot;
  const int a = robot.add_body(RigidBody::from_box(1, Vec3(0.2, 0.05, 0.05)));
  const int b = robot.add_body(RigidBody::from_box(0.5, Vec3(0.2, 0.05, 0.05)));
  JointOptions options;
  options.child_xform.p = Vec3(-0.2, 0, 0);
  const int root = robot.add_joint_revolute(-1, a, options);
  options.parent_xform.p = Vec3(0.2, 0, 0);
  const int hinge = robot.add_joint_revolute(a, b, options);
  robot.add_motor(hinge, 40, -1, 1);
  robot.add_motor(root, 5);
  robot.add_motor(hinge, 2, -10, 10, -3, 3);
  ModelBuilder batch;
  batch.replicate(robot, 37);
  SolverFeatherstoneSettings settings = no_damping();
  settings.num_threads = 2;
  Scene scene(batch, settings);
  for (int u = 0; u < scene.model.actuator_count; ++u) scene.control.actuator_ctrl[u] = 0.37 * (u % 11) - 2;
  for (int d = 0; d < scene.model.joint_dof_count; ++d) scene.control.joint_f[d] = 0.01 * d;
  const VecX qdd = eval_forward_dynamics(scene.model, scene.state, scene.control);
  scene.run(kDt, kDt);
  for (int d = 0; d < scene.model.joint_dof_count; ++d)
    EXPECT_NEAR(scene.state.joint_qd[d], kDt * qdd[d], 1e-12 * (1 + std::abs(kDt * qdd[d]))) << "dof " << d;
}

TEST(SolverFeatherstone, JointSupport) {
  ModelBuilder builder;
  add_box(builder, Vec3::Zero());
  const Model model = builder.finalize();
  const JointSupportMatrix support = SolverFeatherstone(model).joint_support();
  for (const char* joint : {"Revolute", "Prismatic", "Slide", "Ball", "Fixed", "Free"})
    EXPECT_TRUE(support.supports(joint));
  for (const char* joint : {"Distance", "D6", "Cable"}) EXPECT_FALSE(support.supports(joint));
  EXPECT_NE(support.to_string().find("D6: no"), std::string::npos);
  EXPECT_NOVAPHY_ERROR(support.supports("Hinge"), "unknown joint type 'Hinge'");
}

// a float32 block flushes subnormal floats to zero (SubnormalsAsZero): a level slider's velocity of 1e-40,
// below FLT_MIN, steps as zero; float64 keeps it, and the other worlds stay at rest
TEST(Precision, Float32BlocksFlushSubnormalVelocitiesToZero) {
#if !defined(__SSE__)
  GTEST_SKIP() << "subnormals are flushed on x86 only";
#endif
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    ModelBuilder robot, worlds;
    const int slider = robot.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)));
    JointOptions options;
    options.dof.axis = Vec3::UnitX();
    robot.add_joint_prismatic(-1, slider, options);
    worlds.set_precision(precision);
    worlds.replicate(robot, 4);
    Scene scene(worlds);
    const int lanes = scene.solver.batches()->lanes();
    ASSERT_EQ(scene.solver.batches()->block_count(), (4 + lanes - 1) / lanes);  // every world on the blocks
    scene.state.joint_qd[1] = 1e-40;
    scene.run(kDt);
    EXPECT_EQ(scene.state.joint_qd[1], precision == Precision::Float32 ? 0.0 : 1e-40);
    for (const int k : {0, 2, 3}) EXPECT_EQ(scene.state.joint_qd[k], 0.0);
  }
}

// shapes with an empty collision group or mask are left out of the broad phase and never collide
TEST(CollisionPipelineFiltering, VisualOnlyShapesNeverCollide) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int box = add_box(builder, Vec3(0, 0.1, 0));  // overlapping the ground by 0.1
  ShapeOptions visual;
  visual.collision_group = 0;
  builder.add_shape_sphere(box, 0.5, visual);
  visual.collision_group = 1;
  visual.collision_mask = 0;
  builder.add_shape_sphere(box, 0.5, visual);
  Scene scene(builder);
  scene.pipeline.collide(scene.state, scene.contacts);
  EXPECT_EQ(scene.contacts.contact_count, 4);  // the box's corners only
  for (int c = 0; c < scene.contacts.contact_count; ++c) EXPECT_EQ(scene.contacts.contact_shape_b[c], 1);
}

// a chain of Prismatic joints has a constant H: the solver computes it once and keeps its factor
// while the implicit diagonal stays the same; stepping matches a fresh solver (a new H and factor)
// every step, also across a change of drive gains half way
TEST(SolverFeatherstone, PrismaticChainKeepsItsMassMatrix) {
  ModelBuilder builder;
  int parent = -1;
  const Vec3 axes[3] = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0).normalized()};
  for (const Vec3& axis : axes) {
    const int body = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)));
    JointOptions options;
    options.dof.axis = axis;
    options.parent_xform.p = Vec3(0.3, 0, 0);
    builder.add_joint_prismatic(parent, body, options);
    parent = body;
  }
  Scene kept(builder);
  State fresh = kept.state;
  for (int k = 0; k < 120; ++k) {
    if (k == 60)
      for (int d = 0; d < 3; ++d) kept.control.joint_target_ke[d] = 50, kept.control.joint_target_kd[d] = 2;
    kept.solver.step(kept.state, kept.state, kept.control, kept.contacts, kDt);
    SolverFeatherstone once(kept.model);
    once.step(fresh, fresh, kept.control, kept.contacts, kDt);
  }
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(kept.state.joint_q[d], fresh.joint_q[d], 1e-12) << "dof " << d;
  EXPECT_GT(std::abs(kept.state.joint_q[1]), 0.01);  // gravity pulled along the second axis
}

}  // namespace
}  // namespace novaphy
