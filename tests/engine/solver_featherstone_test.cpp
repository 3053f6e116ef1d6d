#include "engine/solver_featherstone.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <memory>

#include "engine/builder.h"
#include "engine/dynamics.h"
#include "engine/mjcf_import.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

const Scalar kDt = 1.0 / 120;

// a finalized scene with its pipeline, contacts, solver, state and control
struct Scene {
  explicit Scene(const ModelBuilder& builder, const SolverFeatherstoneSettings& settings = {})
      : model(builder.finalize()),
        pipeline(model),
        contacts(pipeline.contacts()),
        solver(model, settings),
        state(model.state()),
        control(model.control()) {}

  void run(Scalar seconds, Scalar dt = kDt, const std::function<void()>& after_step = {}) {
    const int steps = static_cast<int>(std::lround(seconds / dt));
    for (int k = 0; k < steps; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, control, contacts, dt);
      if (after_step) after_step();
    }
  }
  Vec3 position(int body) const { return Eigen::Map<const Vec3>(&state.body_q[7 * body]); }
  Vec3 velocity(int body) const { return Eigen::Map<const Vec3>(&state.body_qd[6 * body]); }

  Model model;
  CollisionPipeline pipeline;
  Contacts contacts;
  SolverFeatherstone solver;
  State state;
  Control control;
};

ShapeOptions material(Scalar mu, Scalar restitution = 0) {
  ShapeOptions options;
  options.mu = mu;
  options.restitution = restitution;
  return options;
}

int add_box(ModelBuilder& builder, const Vec3& position, Scalar half = 0.2, Scalar mass = 1, Scalar mu = 0.5) {
  const int body = builder.add_body(RigidBody::from_box(mass, Vec3::Constant(half)), Transform{position});
  builder.add_shape_box(body, Vec3::Constant(half), material(mu));
  return body;
}

SolverFeatherstoneSettings no_damping() {
  SolverFeatherstoneSettings settings;
  settings.angular_damping = 0;
  return settings;
}

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

// the finite checks of a state long enough to be split over threads still name the first bad entry
TEST(SolverFeatherstoneErrors, ANonFiniteEntryOfALargeStateIsNamedOnAnyThreadCount) {
  ModelBuilder world, builder;
  add_box(world, Vec3(0, 0.5, 0));
  builder.replicate(world, 12000);  // 84000 coordinates, 72000 body_f entries
  const Model model = builder.finalize();
  for (const int threads : {1, 2}) {
    SolverFeatherstoneSettings settings;
    settings.num_threads = threads;
    SolverFeatherstone solver(model, settings);
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    State state = model.state();
    const Control control = model.control();
    state.body_f[6 * 11999 + 4] = std::numeric_limits<Scalar>::infinity();
    state.body_f[6 * 11999 + 5] = std::nan("");
    EXPECT_NOVAPHY_ERROR(solver.step(state, state, control, contacts, kDt), "body_f[71998] is not finite: inf");
    state.body_f = model.state().body_f;
    state.joint_q[7 * 9000 + 2] = std::nan("");
    EXPECT_NOVAPHY_ERROR(solver.step(state, state, control, contacts, kDt), "joint_q[63002] is not finite: nan");
  }
}

// the PD targets enter a step only through a nonzero gain: without one, non-finite targets are not read (the
// steps equal those with finite targets, on the batched and the scalar path); with one, the first is named
// and nothing is written
TEST(SolverFeatherstoneErrors, PdTargetsAreCheckedWhenAGainReadsThem) {
  ModelBuilder builder;
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(0, 0.25, 0);  // each hinge at the top of its link
  const int upper = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  builder.add_joint_revolute(-1, upper, options);
  const int lower = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  options.parent_xform.p = Vec3(0, -0.25, 0);
  builder.add_joint_revolute(upper, lower, options);
  for (const bool batched : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = batched;
    Scene finite(builder, settings), bad(builder, settings);
    finite.state.joint_q[0] = bad.state.joint_q[0] = 0.5;
    bad.control.joint_target_pos[0] = std::nan("");
    bad.control.joint_target_vel[1] = std::numeric_limits<Scalar>::infinity();
    finite.run(0.5);
    bad.run(0.5);
    EXPECT_EQ(bad.state.joint_q, finite.state.joint_q) << "batched " << batched;
    EXPECT_EQ(bad.state.joint_qd, finite.state.joint_qd) << "batched " << batched;
    EXPECT_EQ(bad.state.body_q, finite.state.body_q) << "batched " << batched;

    const State before = bad.state;
    bad.control.joint_target_kd[1] = 1;
    EXPECT_NOVAPHY_ERROR(bad.solver.step(bad.state, bad.state, bad.control, bad.contacts, kDt),
                         "joint_target_pos[0] is not finite: nan");
    bad.control.joint_target_pos[0] = 0;
    EXPECT_NOVAPHY_ERROR(bad.solver.step(bad.state, bad.state, bad.control, bad.contacts, kDt),
                         "joint_target_vel[1] is not finite: inf");
    EXPECT_EQ(bad.state.joint_q, before.joint_q);
    EXPECT_EQ(bad.state.body_q, before.body_q);
  }
}

TEST(SolverFeatherstoneErrors, BadStepArguments) {
  ModelBuilder builder;
  builder.add_ground_plane();
  add_box(builder, Vec3(0, 0.5, 0));
  Scene scene(builder);
  const State before = scene.state;
  for (const Scalar dt : {0.0, -0.01, std::nan("")})
    EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, dt),
                         "dt must be finite and > 0");

  ModelBuilder other;
  other.add_ground_plane();
  add_box(other, Vec3(0, 0.5, 0));
  add_box(other, Vec3(0, 1.5, 0));
  Scene foreign(other);
  EXPECT_NOVAPHY_ERROR(scene.solver.step(foreign.state, scene.state, scene.control, scene.contacts, kDt),
                       "state or control from another model");
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, foreign.contacts, kDt),
                       "contacts buffer is from another model");
  EXPECT_NOVAPHY_ERROR(scene.pipeline.collide(scene.state, foreign.contacts),
                       "contacts buffer was not made by this pipeline");

  scene.solver.settings.num_iterations = -1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.num_iterations must be >= 0, got -1");
  scene.solver.settings = {};
  scene.solver.settings.erp = 1.5;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.erp must be in [0, 1], got 1.5");
  scene.solver.settings = {};
  scene.solver.settings.update_mass_matrix_interval = 0;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.update_mass_matrix_interval must be >= 1, got 0");
  scene.solver.settings = {};
  scene.solver.settings.aba_min_dofs = -1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.aba_min_dofs must be >= 0, got -1");
  scene.solver.settings = {};
  scene.solver.settings.stream_body_output_above = -1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.stream_body_output_above must be >= 0 bytes, got -1");
  scene.solver.settings = {};
  scene.solver.settings.coriolis_implicitness = 1.5;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.coriolis_implicitness must be in [0, 1], got 1.5");
  scene.solver.settings = {};
  scene.control.joint_f[2] = std::nan("");
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "joint_f[2] is not finite: nan");
  // nothing was written by the failed steps
  EXPECT_EQ(scene.state.joint_q, before.joint_q);
  EXPECT_EQ(scene.state.body_q, before.body_q);

  // a velocity no double can hold after the step: the step raises and leaves the state as it was
  scene.control.joint_f[2] = 0;
  scene.control.joint_f[3] = 1e308;
  scene.state.joint_qd[3] = 1e308;
  const State fast = scene.state;
  scene.solver.settings.on_divergence = DivergencePolicy::Raise;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, 1.0),
                       "step diverged in articulation 0");
  EXPECT_EQ(scene.state.joint_q, fast.joint_q);
  EXPECT_EQ(scene.state.joint_qd, fast.joint_qd);

  SolverFeatherstoneSettings bad;
  bad.friction_smoothing = -1;
  EXPECT_NOVAPHY_ERROR(SolverFeatherstone(scene.model, bad), "settings.friction_smoothing must be in [0, 1], got -1");
  bad = {};
  bad.pgs_tolerance = std::nan("");
  EXPECT_NOVAPHY_ERROR(SolverFeatherstone(scene.model, bad), "settings.pgs_tolerance must be in [0, 1000000], got nan");
}

// ---- determinism: same inputs, bit-identical states ----

// 9 sprung quadrupeds and a pile of boxes: contacts between robots, boxes and the ground
ModelBuilder contact_rich_scene(int first_robot = 0) {
  ModelBuilder builder;
  builder.add_plane(Vec3::UnitZ(), 0);
  ImportOptions options;
  options.static_shapes = false;
  for (int k = first_robot; k < first_robot + 9; ++k) {
    options.xform.p = Vec3(0.7 * (k % 3), 0.5 * (k / 3), 0.3);
    import_mjcf(builder, NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  }
  for (int k = 0; k < 10; ++k) add_box(builder, Vec3(0.1 * k, 0.2 * (k % 3), 1.0 + 0.3 * k), 0.1, 1, 0.7);
  builder.set_gravity(Vec3(0, 0, -9.81));
  return builder;
}

std::size_t state_hash(const State& state) {
  std::size_t h = 1469598103934665603ull;
  for (const auto* field : {&state.joint_q, &state.joint_qd, &state.body_q, &state.body_qd})
    for (const Scalar x : *field) h = (h ^ std::hash<Scalar>{}(x)) * 1099511628211ull;
  return h;
}

std::size_t run_hash(const ModelBuilder& builder, int threads, int steps = 1000) {
  SolverFeatherstoneSettings settings;
  settings.num_threads = threads;
  Scene scene(builder, settings);
  scene.run(steps * 0.005, 0.005);
  return state_hash(scene.state);
}

TEST(Determinism, RunToRunAndAnyThreadCount) {
  const ModelBuilder builder = contact_rich_scene();
  const std::size_t one = run_hash(builder, 1);
  EXPECT_EQ(run_hash(builder, 1), one);
  EXPECT_EQ(run_hash(builder, 2), one);
  EXPECT_EQ(run_hash(builder, 3), one);
}

// a robot's trajectory does not depend on where its articulation sits in the model
TEST(Determinism, ArticulationPositionInTheModel) {
  ModelBuilder alone;
  alone.add_plane(Vec3::UnitZ(), 0);
  ImportOptions options;
  options.static_shapes = false;
  options.xform.p = Vec3(0, 0, 0.3);
  const MujocoImport a = import_mjcf(alone, NOVAPHY_SCENE_DIR "/quadruped.xml", options);

  ModelBuilder crowd;
  crowd.add_plane(Vec3::UnitZ(), 0);
  for (int k = 1; k <= 3; ++k) {
    ImportOptions far = options;
    far.xform.p = Vec3(5.0 * k, 0, 0.3);
    import_mjcf(crowd, NOVAPHY_SCENE_DIR "/quadruped.xml", far);
  }
  const MujocoImport b = import_mjcf(crowd, NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  alone.set_gravity(Vec3(0, 0, -9.81));
  crowd.set_gravity(Vec3(0, 0, -9.81));

  Scene first(alone), second(crowd);
  first.run(2, 0.005);
  second.run(2, 0.005);
  const int nq = first.model.joint_coord_count, nv = first.model.joint_dof_count;
  const std::vector<Scalar> q1(first.state.joint_q.begin(), first.state.joint_q.end());
  const std::vector<Scalar> q2(second.state.joint_q.begin() + b.q_begin, second.state.joint_q.begin() + b.q_begin + nq);
  const std::vector<Scalar> v1(first.state.joint_qd.begin(), first.state.joint_qd.end());
  const std::vector<Scalar> v2(second.state.joint_qd.begin() + b.qd_begin,
                               second.state.joint_qd.begin() + b.qd_begin + nv);
  EXPECT_EQ(q1, q2);
  EXPECT_EQ(v1, v2);
  EXPECT_EQ(a.q_begin, 0);
}

TEST(Determinism, RestoredCheckpointContinuesIdentically) {
  // warm starting keeps impulses in the contacts buffer and the solver, outside the state: off here
  SolverFeatherstoneSettings settings;
  settings.use_warmstarting = false;
  Scene scene(contact_rich_scene(), settings);
  scene.run(0.5, 0.005);
  State checkpoint = scene.model.state();
  checkpoint.assign(scene.state);
  scene.run(0.5, 0.005);
  const std::size_t straight = state_hash(scene.state);
  scene.state.assign(checkpoint);
  scene.run(0.5, 0.005);
  EXPECT_EQ(state_hash(scene.state), straight);

  ModelBuilder other;
  add_box(other, Vec3::Zero());
  const Model small = other.finalize();
  State wrong = small.state();
  EXPECT_NOVAPHY_ERROR(wrong.assign(scene.state), "assign: the other state belongs to a model with");
}

// ---- the divergence guard ----

// four pendulums side by side; the third is thrown at a speed beyond divergence_speed
ModelBuilder pendulums() {
  ModelBuilder builder;
  for (int k = 0; k < 4; ++k) {
    const int link = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.parent_xform.p = Vec3(k, 2, 0);
    options.child_xform.p = Vec3(-0.25, 0, 0);
    builder.add_joint_revolute(-1, link, options);
  }
  return builder;
}

TEST(DivergenceGuard, FlagsOnlyTheDivergedArticulationAndKeepsItsState) {
  Scene calm(pendulums()), wild(pendulums());
  wild.state.joint_qd[2] = 2e6;
  const std::vector<Scalar> q_before(wild.state.joint_q), qd_before(wild.state.joint_qd);
  calm.run(kDt);
  wild.run(kDt);
  EXPECT_EQ(wild.solver.diverged(), (std::vector<std::uint8_t>{0, 0, 1, 0}));
  EXPECT_EQ(wild.state.joint_q[2], q_before[2]);  // kept as it was
  EXPECT_EQ(wild.state.joint_qd[2], qd_before[2]);
  for (const int k : {0, 1, 3}) {  // the others stepped exactly as without it
    EXPECT_EQ(wild.state.joint_q[k], calm.state.joint_q[k]);
    EXPECT_EQ(wild.state.joint_qd[k], calm.state.joint_qd[k]);
  }
  wild.state.joint_qd[2] = 0;
  wild.run(kDt);
  EXPECT_EQ(wild.solver.diverged(), (std::vector<std::uint8_t>{0, 0, 0, 0}));
}

TEST(DivergenceGuard, ResetRestartsFromTheInitialState) {
  SolverFeatherstoneSettings settings;
  settings.on_divergence = DivergencePolicy::Reset;
  Scene wild(pendulums(), settings);
  wild.run(0.5);
  wild.state.joint_qd[2] = std::numeric_limits<Scalar>::max();
  wild.run(kDt);
  EXPECT_EQ(wild.solver.diverged()[2], 1);
  EXPECT_EQ(wild.state.joint_q[2], wild.model.joint_q0[2]);
  EXPECT_EQ(wild.state.joint_qd[2], 0);
  EXPECT_NE(wild.state.joint_q[1], wild.model.joint_q0[1]);  // the others went on swinging
}

// four worlds of one pendulum, in one block: the blocks write each world's new state as they step it,
// all but the worlds they flag
ModelBuilder pendulum_worlds(Precision precision) {
  ModelBuilder robot, worlds;
  const int link = robot.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.parent_xform.p = Vec3(0, 2, 0);
  options.child_xform.p = Vec3(-0.25, 0, 0);
  robot.add_joint_revolute(-1, link, options);
  worlds.set_precision(precision);
  worlds.replicate(robot, 4);
  return worlds;
}

TEST(DivergenceGuard, AFlaggedWorldOfABlockKeepsItsStateAndBodies) {
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    Scene calm(pendulum_worlds(precision)), wild(pendulum_worlds(precision));
    const int lanes = wild.solver.batches()->lanes();  // world 2 shares its block with world 3 at least
    ASSERT_EQ(wild.solver.batches()->block_count(), (4 + lanes - 1) / lanes);
    calm.run(0.1);
    wild.run(0.1);
    wild.state.joint_qd[2] = 2e6;
    const State before = wild.state;
    calm.run(kDt);
    wild.run(kDt);
    EXPECT_EQ(wild.solver.diverged(), (std::vector<std::uint8_t>{0, 0, 1, 0}));
    EXPECT_EQ(wild.state.joint_q[2], before.joint_q[2]);
    EXPECT_EQ(wild.state.joint_qd[2], before.joint_qd[2]);
    // its bodies from its kept state
    State fk = wild.state;
    eval_fk(wild.model, fk);
    for (int m = 0; m < 7; ++m) EXPECT_NEAR(wild.state.body_q[7 * 2 + m], fk.body_q[7 * 2 + m], 1e-12);
    for (int m = 0; m < 6; ++m) EXPECT_NEAR(wild.state.body_qd[6 * 2 + m], fk.body_qd[6 * 2 + m], 1e-9);
    for (const int k : {0, 1, 3}) {  // the others stepped exactly as without it
      EXPECT_EQ(wild.state.joint_q[k], calm.state.joint_q[k]);
      EXPECT_EQ(wild.state.joint_qd[k], calm.state.joint_qd[k]);
      for (int m = 0; m < 7; ++m) EXPECT_EQ(wild.state.body_q[7 * k + m], calm.state.body_q[7 * k + m]);
    }
  }
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

// a mass matrix that is not positive definite in one world (its link made massless on the Model, as no
// builder call allows) raises; that world is left as it was, and under Raise every world is
TEST(SolverFeatherstoneErrors, AFailedMassMatrixLeavesItsWorldAsItWas) {
  for (const DivergencePolicy policy : {DivergencePolicy::Flag, DivergencePolicy::Raise}) {
    Model model = pendulum_worlds(Precision::Float32).finalize();
    model.body_mass[1] = 0;
    std::fill_n(model.body_inertia.begin() + 9, 9, 0);
    SolverFeatherstoneSettings settings;
    settings.on_divergence = policy;
    SolverFeatherstone solver(model, settings);
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    State state = model.state();
    const State before = state;
    EXPECT_NOVAPHY_ERROR(solver.step(state, state, model.control(), contacts, kDt),
                         "articulation 1: mass matrix is not positive definite at dof 1");
    EXPECT_EQ(state.joint_q[1], before.joint_q[1]);
    EXPECT_EQ(state.joint_qd[1], before.joint_qd[1]);
    for (int m = 0; m < 7; ++m) EXPECT_EQ(state.body_q[7 + m], before.body_q[7 + m]);
    if (policy == DivergencePolicy::Raise) {
      EXPECT_EQ(state.joint_q, before.joint_q);
      EXPECT_EQ(state.joint_qd, before.joint_qd);
      EXPECT_EQ(state.body_q, before.body_q);
      EXPECT_EQ(state.body_qd, before.body_qd);
    } else {  // the others were stepped as they went (the one exception to "nothing is written")
      EXPECT_NE(state.joint_qd[0], before.joint_qd[0]);
    }
  }
}

// a body whose step overflows to infinity while it rests on another: no NaN crosses the contact
TEST(DivergenceGuard, NoNanSpreadsThroughContacts) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int bottom = add_box(builder, Vec3(0, 0.2, 0));
  const int top = add_box(builder, Vec3(0, 0.6, 0));
  Scene scene(builder);
  scene.run(0.5);
  scene.state.joint_qd[6 + 4] = 1e308;  // the top box's Free dofs: [w; v]
  scene.control.joint_f[6 + 4] = 1e308;
  scene.pipeline.collide(scene.state, scene.contacts);
  scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, 1.0);
  EXPECT_EQ(scene.solver.diverged(), (std::vector<std::uint8_t>{0, 1}));
  for (const Scalar x : scene.state.body_q) EXPECT_TRUE(std::isfinite(x));
  for (int c = 0; c < 3 * scene.contacts.contact_count; ++c)
    EXPECT_TRUE(std::isfinite(scene.contacts.contact_impulse[c]));
  EXPECT_NEAR(scene.position(bottom).y(), 0.2, 0.01);
  EXPECT_NEAR(scene.position(top).y(), 0.6, 0.01);
}

// ---- every setting changes the computation ----

Scalar tower_top_error(int iterations) {
  ModelBuilder builder;
  builder.add_ground_plane();
  int top = -1;
  for (int k = 0; k < 5; ++k) top = add_box(builder, Vec3(0, 0.2 + 0.4 * k, 0));
  SolverFeatherstoneSettings settings;
  settings.num_iterations = iterations;
  Scene scene(builder, settings);
  scene.run(1);
  return std::abs(scene.position(top).y() - 1.8);
}

TEST(SolverFeatherstoneSettingsEffect, NumIterations) { EXPECT_GT(tower_top_error(1), 5 * tower_top_error(30)); }

// a box started 2 cm inside the ground is pushed out until the slop is left
Scalar rest_depth(const std::function<void(SolverFeatherstoneSettings&)>& configure, Scalar seconds = 3) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int box = add_box(builder, Vec3(0, 0.18, 0));
  SolverFeatherstoneSettings settings;
  configure(settings);
  Scene scene(builder, settings);
  scene.run(seconds);
  return 0.2 - scene.position(box).y();
}

TEST(SolverFeatherstoneSettingsEffect, LinearSlop) {
  EXPECT_NEAR(rest_depth([](auto& s) { s.linear_slop = 0.001; }), 0.001, 1e-4);
  EXPECT_NEAR(rest_depth([](auto& s) { s.linear_slop = 0.01; }), 0.01, 1e-4);
}

TEST(SolverFeatherstoneSettingsEffect, Erp) {
  // one step removes about erp of the penetration beyond the slop
  for (const Scalar erp : {0.1, 0.5}) {
    const Scalar depth = rest_depth([&](auto& s) { s.erp = erp; }, kDt);
    const Scalar expected = 0.02 - erp * (0.02 - 0.001);
    EXPECT_NEAR(depth, expected, 0.1 * (0.02 - expected)) << "erp " << erp;
  }
}

TEST(SolverFeatherstoneSettingsEffect, Cfm) {
  // a soft contact settles deeper by cfm * lambda * dt / erp, lambda = m g dt / 4 per corner
  const Scalar stiff = rest_depth([](auto& s) { s.cfm = 1e-6; });
  const Scalar soft = rest_depth([](auto& s) { s.cfm = 1.0; });
  const Scalar lambda = 9.81 * kDt / 4;
  EXPECT_NEAR(soft - stiff, 1.0 * lambda * kDt / 0.2, 0.1 * lambda * kDt / 0.2);
}

// after a second of normal solving, iterations stop: only warm-started impulses hold the box up
Scalar drop_without_iterations(bool use_warmstarting, Scalar factor) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int box = add_box(builder, Vec3(0, 0.2, 0));
  Scene scene(builder);
  scene.run(1);
  const Scalar y = scene.position(box).y();
  scene.solver.settings.num_iterations = 0;
  scene.solver.settings.use_warmstarting = use_warmstarting;
  scene.solver.settings.warmstarting_factor = factor;
  scene.run(0.5);
  return y - scene.position(box).y();
}

TEST(SolverFeatherstoneSettingsEffect, WarmstartingFactor) {
  EXPECT_LT(drop_without_iterations(true, 1.0), 1e-3);
  EXPECT_GT(drop_without_iterations(true, 0.5), 0.01);
}

TEST(SolverFeatherstoneSettingsEffect, UseWarmstarting) { EXPECT_GT(drop_without_iterations(false, 1.0), 0.5); }

TEST(SolverFeatherstoneSettingsEffect, RestitutionThreshold) {
  for (const Scalar threshold : {0.2, 10.0}) {
    ModelBuilder builder;
    builder.add_ground_plane(0, material(0.5, 0.8));
    const int ball = builder.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0, 1.1, 0)});
    builder.add_shape_sphere(ball, 0.1, material(0.5, 0.8));
    SolverFeatherstoneSettings settings;
    settings.restitution_threshold = threshold;
    Scene scene(builder, settings);
    Scalar rebound = 0;
    scene.run(0.8, kDt, [&] { rebound = std::max(rebound, scene.velocity(ball).y()); });
    // impact at sqrt(2 g) = 4.4 m/s: above the low threshold it bounces at 0.8 of that; below the
    // high one only the position correction of the impact's penetration lifts it (erp, see README)
    if (threshold < 4)
      EXPECT_GT(rebound, 3.0);
    else
      EXPECT_LT(rebound, 0.1 * 0.8 * 4.4);
  }
}

TEST(SolverFeatherstoneSettingsEffect, AngularDamping) {
  for (const Scalar damping : {0.0, 0.5}) {
    ModelBuilder builder(Vec3::Zero());
    builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.2, 0.3)));
    SolverFeatherstoneSettings settings;
    settings.angular_damping = damping;
    Scene scene(builder, settings);
    scene.state.joint_qd[1] = 3.0;  // spin about the y principal axis
    scene.run(1);
    EXPECT_NEAR(scene.state.joint_qd[1], 3.0 * std::pow(1 - damping * kDt, 120), 1e-9) << "damping " << damping;
  }
}

// a contact-free double pendulum: chaotic enough that any change in H shows
std::vector<Scalar> double_pendulum(const std::function<void(SolverFeatherstoneSettings&)>& configure,
                                    Scalar seconds = 2) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  const int b = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.25, 0, 0);
  builder.add_joint_revolute(-1, a, options);
  options.parent_xform.p = Vec3(0.25, 0, 0);
  builder.add_joint_revolute(a, b, options);
  SolverFeatherstoneSettings settings = no_damping();
  configure(settings);
  Scene scene(builder, settings);
  scene.run(seconds);
  return scene.state.joint_q;
}

Scalar max_difference(const std::vector<Scalar>& x, const std::vector<Scalar>& y) {
  Scalar d = 0;
  for (size_t k = 0; k < x.size(); ++k) d = std::max(d, std::abs(x[k] - y[k]));
  return d;
}

TEST(SolverFeatherstoneSettingsEffect, UpdateMassMatrixInterval) {
  const auto every = double_pendulum([](auto&) {}, 0.5);
  const auto reused = double_pendulum([](auto& s) { s.update_mass_matrix_interval = 4; }, 0.5);
  EXPECT_GT(max_difference(every, reused), 1e-6);  // a stale H changes the trajectory ...
  EXPECT_LT(max_difference(every, reused), 0.2);   // ... but only a little at this cadence
}

TEST(SolverFeatherstoneSettingsEffect, UseTileGemmGivesTheSameMassMatrix) {
  const auto crba = double_pendulum([](auto&) {});
  const auto gemm = double_pendulum([](auto& s) { s.use_tile_gemm = true; });
  EXPECT_LT(max_difference(crba, gemm), 1e-9);
  const auto scalar_gemm = double_pendulum([](auto& s) {
    s.use_tile_gemm = true;
    s.use_batch_kernels = false;
  });
  EXPECT_LT(max_difference(crba, scalar_gemm), 1e-9);
}

TEST(SolverFeatherstoneSettingsEffect, FuseCholeskyGivesTheSameSolution) {
  const auto fused = double_pendulum([](auto&) {});
  const auto split = double_pendulum([](auto& s) { s.fuse_cholesky = false; });
  EXPECT_LT(max_difference(fused, split), 1e-12);
}

// the ABA path (O(n) factor and solves) against CRBA + Cholesky on the standing quadruped: contacts,
// limits, springs, damping and PD drives all go through M^-1
TEST(SolverFeatherstoneSettingsEffect, AbaMinDofsGivesTheSameTrajectory) {
  auto run = [](int aba_min_dofs) {
    ModelBuilder builder;
    import_mjcf(builder, NOVAPHY_SCENE_DIR "/quadruped.xml");
    SolverFeatherstoneSettings settings;
    settings.aba_min_dofs = aba_min_dofs;
    Scene scene(builder, settings);
    for (int k = 0; k < scene.model.joint_dof_count; ++k) {
      scene.control.joint_target_ke[k] = 20;
      scene.control.joint_target_kd[k] = 1;
      scene.control.joint_target_pos[k] = 0.3;
    }
    scene.run(1.0, 0.005);
    EXPECT_GT(scene.contacts.contact_count, 0);
    return scene.state.joint_q;
  };
  const std::vector<Scalar> crba = run(1000), aba = run(0);
  EXPECT_LT(max_difference(crba, aba), 1e-8);
}

// a chain of revolute box links (one per mass) about Z, joined end to end, horizontal at q = 0, no XML
ModelBuilder revolute_chain(const std::vector<Scalar>& masses, const Vec3& half_extents) {
  ModelBuilder builder;
  int parent = -1;
  for (const Scalar m : masses) {
    const int link = builder.add_body(RigidBody::from_box(m, half_extents));
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.parent_xform.p = parent < 0 ? Vec3::Zero() : Vec3(half_extents.x(), 0, 0);
    options.child_xform.p = Vec3(-half_extents.x(), 0, 0);
    builder.add_joint_revolute(parent, link, options);
    parent = link;
  }
  return builder;
}

// n links 0.1 m long of 0.1 kg
ModelBuilder long_chain(int n) { return revolute_chain(std::vector<Scalar>(n, 0.1), Vec3(0.05, 0.01, 0.01)); }

// 1000 links: the solver takes ABA (O(n)) by default and agrees with CRBA + Cholesky (O(n^3)) over
// ten steps; half a second later the chain has fallen, finite
TEST(Extremes, ThousandLinkChainStepsOnAbaAndAgreesWithCrba) {
  const int n = 1000;
  SolverFeatherstoneSettings crba_settings;
  crba_settings.aba_min_dofs = n + 1;
  Scene aba(long_chain(n)), crba(long_chain(n), crba_settings);
  ASSERT_GE(n, aba.solver.settings.aba_min_dofs);
  aba.run(0.01, 0.001);
  crba.run(0.01, 0.001);
  Scalar largest = 0;
  for (const Scalar v : crba.state.joint_qd) largest = std::max(largest, std::abs(v));
  // relative 4e-7 seen: the dense factor of this H loses digits to its conditioning (kappa ~ n^4)
  EXPECT_LT(max_difference(aba.state.joint_qd, crba.state.joint_qd), 1e-5 * largest);
  aba.run(0.49, 0.001);
  for (const Scalar q : aba.state.joint_q) ASSERT_TRUE(std::isfinite(q));
  const Vec3 tip = aba.position(n - 1);
  EXPECT_LT(tip.y(), -1.0);  // the chain fell under gravity
}

// a box sliding diagonally to the tangent axes: the circular cone decelerates it at mu g, box
// friction clamps each tangent to mu lambda_n and decelerates it at sqrt(2) mu g
TEST(SolverFeatherstoneSettingsEffect, FrictionSmoothing) {
  for (const Scalar smoothing : {0.0, 1.0}) {
    ModelBuilder builder;
    builder.add_ground_plane(0, material(0.5));
    const int box = add_box(builder, Vec3(0, 0.2, 0), 0.2, 1, 0.5);
    SolverFeatherstoneSettings settings = no_damping();
    settings.friction_smoothing = smoothing;
    Scene scene(builder, settings);
    const Vec3 diagonal = Vec3(1, 0, 1).normalized();
    Eigen::Map<Vec3>(&scene.state.joint_qd[3]) = 3.0 * diagonal;  // Free dofs [w; v]
    scene.run(kDt);
    const Scalar v0 = scene.velocity(box).dot(diagonal);
    scene.run(0.25);
    const Scalar deceleration = (v0 - scene.velocity(box).dot(diagonal)) / 0.25;
    const Scalar expected = (smoothing == 0 ? std::sqrt(2.0) : 1.0) * 0.5 * 9.81;
    EXPECT_NEAR(deceleration, expected, 0.05 * expected) << "friction_smoothing " << smoothing;
    EXPECT_LT(scene.velocity(box).cross(diagonal).norm(), 1e-6);  // keeps its direction
  }
}

}  // namespace
}  // namespace novaphy

namespace novaphy {
namespace {

// a pendulum of links 0.5 m long with the given masses, horizontal at q = 0, no damping
ModelBuilder pendulum_chain(const std::vector<Scalar>& masses) {
  return revolute_chain(masses, Vec3(0.25, 0.02, 0.02));
}

// largest |E(t) - E(0)| over a run, relative to the energy scale m g l of the first link
Scalar energy_drift(Scene& scene, Scalar seconds, Scalar dt) {
  const Scalar e0 = eval_energy(scene.model, scene.state), scale = scene.model.body_mass[0] * 9.81 * 0.5;
  Scalar worst = 0;
  scene.run(seconds, dt, [&] { worst = std::max(worst, std::abs(eval_energy(scene.model, scene.state) - e0)); });
  return worst / scale;
}

// links of 1 kg alternating with links a thousand and a million times lighter: the light links do
// not change the motion (measured drift 0.157 m g l for both ratios in 2 s at dt = 1 ms)
TEST(Extremes, AdjacentLinkMassRatios) {
  std::vector<Scalar> drift;
  for (const Scalar ratio : {1e-3, 1e-6}) {
    Scene scene(pendulum_chain({1, ratio, 1, ratio}), no_damping());
    drift.push_back(energy_drift(scene, 2, 1e-3));
    for (const Scalar q : scene.state.joint_q) ASSERT_TRUE(std::isfinite(q)) << "ratio " << ratio;
  }
  EXPECT_LT(drift[0], 0.25);
  EXPECT_LT(std::abs(drift[1] - drift[0]), 0.01);
}

// 1e5 steps of a double pendulum released horizontal, no damping: semi-implicit Euler keeps its
// energy within 2 % of m g l at dt = 0.1 ms (measured 1.3 %; at dt = 1 ms it loses 24 % in 10 s)
TEST(Extremes, ConservativeDoublePendulumEnergy) {
  Scene scene(pendulum_chain({1, 1}), no_damping());
  EXPECT_LT(energy_drift(scene, 10, 1e-4), 0.02);
}

// 100 rad/s about the intermediate axis, 20 000 steps of 0.1 ms without gravity: the spin flips
// (Dzhanibekov) either way; its energy drifts by the given share at the given coriolis_implicitness
Scalar spin_energy_drift(Scalar implicitness, Scalar* lowest_spin) {
  ModelBuilder builder(Vec3::Zero());
  builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.1, 0.2)));  // y: the intermediate axis
  SolverFeatherstoneSettings settings = no_damping();
  settings.coriolis_implicitness = implicitness;
  Scene scene(builder, settings);
  scene.state.joint_qd[0] = 0.01;
  scene.state.joint_qd[1] = 100;
  const Scalar e0 = eval_energy(scene.model, scene.state);
  Scalar worst = 0;
  *lowest_spin = 100;
  scene.run(2, 1e-4, [&] {
    worst = std::max(worst, std::abs(eval_energy(scene.model, scene.state) / e0 - 1));
    const Transform X = Transform::from_array(&scene.state.body_q[0]);
    *lowest_spin = std::min(*lowest_spin, (X.q.conjugate() * Eigen::Map<const Vec3>(&scene.state.joint_qd[0])).y());
  });
  return worst;
}

// explicit: 7.6 % energy gained; the linearised midpoint: 9e-6 (measured); asserted: 1 %
TEST(Extremes, SpinAboutTheIntermediateAxisFlipsAndKeepsItsEnergy) {
  Scalar lowest = 0;
  EXPECT_LT(spin_energy_drift(0.5, &lowest), 0.01);
  EXPECT_LT(lowest, -90);  // the body-frame spin turned over
  EXPECT_GT(spin_energy_drift(0, &lowest), 0.05);
  EXPECT_LT(lowest, -90);
}

// the 15-link chain (bench/scenes/chain15.xml, no floor) falling from horizontal for 10 s at
// dt = 1/120 s: its whipping tip blows up with explicit Coriolis forces (the guard flags it), and
// stays finite with the linearised midpoint
int chain_diverged_steps(Scalar implicitness, Scalar* energy_change) {
  ModelBuilder builder;
  ImportOptions options;
  options.static_shapes = false;
  import_mjcf(builder, NOVAPHY_SCENE_DIR "/chain15.xml", options);
  SolverFeatherstoneSettings settings = no_damping();
  settings.coriolis_implicitness = implicitness;
  Scene scene(builder, settings);
  const Scalar e0 = eval_energy(scene.model, scene.state);
  int diverged = 0;
  scene.run(10, 1.0 / 120, [&] { diverged += scene.solver.diverged()[0]; });
  *energy_change = eval_energy(scene.model, scene.state) - e0;
  return diverged;
}

TEST(Extremes, WhippingChainAtLargeSteps) {
  Scalar change = 0;
  EXPECT_GT(chain_diverged_steps(0, &change), 0);
  EXPECT_EQ(chain_diverged_steps(0.5, &change), 0);
  EXPECT_LT(change, 0);  // joint damping (0.05 in the file) only takes energy out
}

TEST(Extremes, QuaternionNormsAfterAMillionSteps) {
  ModelBuilder builder(Vec3::Zero());
  builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.1, 0.2)));
  Scene scene(builder, no_damping());
  scene.state.joint_qd[0] = 3;
  scene.state.joint_qd[1] = 7;
  scene.state.joint_qd[2] = 1;
  scene.run(100, 1e-4);
  EXPECT_LT(std::abs(Eigen::Map<const Eigen::Matrix<Scalar, 4, 1>>(&scene.state.joint_q[3]).norm() - 1), 1e-12);
}

// kp = 1e6 on a 10 g link at dt = 1/120 s: the implicit drive reaches its target without overshoot
TEST(Extremes, StiffPdDriveOnALightLink) {
  ModelBuilder builder;
  const int link = builder.add_body(RigidBody::from_box(0.01, Vec3(0.05, 0.01, 0.01)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.05, 0, 0);
  builder.add_joint_revolute(-1, link, options);
  Scene scene(builder);
  scene.control.joint_target_ke[0] = 1e6;
  scene.control.joint_target_kd[0] = 10;
  scene.control.joint_target_pos[0] = 0.5;
  Scalar highest = 0;
  scene.run(1, kDt, [&] { highest = std::max(highest, scene.state.joint_q[0]); });
  EXPECT_LT(std::abs(scene.state.joint_q[0] - 0.5), 1e-6);
  EXPECT_LT(highest, 0.5 + 1e-6);
}

// a pendulum swung 0.6 s with dt from 1/30 s to 0.1 ms against dt = 10 us: first order, the
// angle error below 1.5 dt rad (measured 1.1-1.23 dt)
TEST(Extremes, TimeStepsFromAThirtiethToTenMicroseconds) {
  auto swing = [](Scalar dt) {
    Scene scene(pendulum_chain({1}), no_damping());
    scene.run(0.6, dt);
    return scene.state.joint_q[0];
  };
  const Scalar reference = swing(1e-5);
  ASSERT_TRUE(std::isfinite(reference));
  for (const Scalar dt : {1.0 / 30, 1.0 / 120, 1e-3, 1e-4}) EXPECT_LT(std::abs(swing(dt) - reference), 1.5 * dt);
}

// ten 0.4 m boxes stacked: they stand 10 s, the worst moving 2.7 cm
TEST(Extremes, TenBoxStack) {
  ModelBuilder builder;
  builder.add_ground_plane();
  std::vector<int> boxes;
  for (int k = 0; k < 10; ++k) boxes.push_back(add_box(builder, Vec3(0, 0.2 + 0.4 * k, 0)));
  Scene scene(builder);
  scene.run(10);
  for (int k = 0; k < 10; ++k)
    EXPECT_LT((scene.position(boxes[k]) - Vec3(0, 0.2 + 0.4 * k, 0)).norm(), 0.05) << "box " << k;
}

// a 100 kg box on a 1 kg box: 100 PGS iterations keep it on top for 10 s (4 cm of creep); the
// default 20 do not, the heavy box creeps off within 10 s (a limit of Gauss-Seidel at this mass ratio)
TEST(Extremes, HeavyBoxOnALightOne) {
  auto heavy_after = [](int iterations) {
    ModelBuilder builder;
    builder.add_ground_plane();
    add_box(builder, Vec3(0, 0.2, 0), 0.2, 1);
    const int heavy = add_box(builder, Vec3(0, 0.6, 0), 0.2, 100);
    SolverFeatherstoneSettings settings;
    settings.num_iterations = iterations;
    Scene scene(builder, settings);
    scene.run(10);
    return scene.position(heavy);
  };
  const Vec3 held = heavy_after(100);
  EXPECT_LT(std::abs(held.y() - 0.6), 0.005);
  EXPECT_LT(std::hypot(held.x(), held.z()), 0.05);
  EXPECT_LT(heavy_after(20).y(), 0.5);  // the documented limit: fallen off
}

}  // namespace
}  // namespace novaphy

namespace novaphy {
namespace {

TEST(SolverFeatherstoneSettingsEffect, ProfileStagesTimesEachStageOnlyWhenOn) {
  ModelBuilder builder;
  builder.add_ground_plane();
  add_box(builder, Vec3(0, 0.19, 0));
  Scene scene(builder);
  scene.run(0.1);
  EXPECT_EQ(scene.solver.stage_seconds().steps, 0);
  EXPECT_EQ(scene.solver.stage_seconds().dynamics, 0);
  scene.solver.settings.profile_stages = true;
  scene.run(0.1);
  const SolverStageSeconds& t = scene.solver.stage_seconds();
  EXPECT_EQ(t.steps, 12);
  for (const double seconds : {t.dynamics, t.contact_rows, t.solve, t.integrate}) EXPECT_GT(seconds, 0);
  scene.solver.reset_stage_seconds();
  EXPECT_EQ(scene.solver.stage_seconds().steps, 0);
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

}  // namespace
}  // namespace novaphy

namespace novaphy {
namespace {

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
