// The divergence guard: a world whose step diverges (speed, a contact too deep, an energy blow-up) flagged, reset or
// raised by its policy while the others step on as without it, and no NaN crossing a contact.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "solver_test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

using namespace solver_test;

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

// under Reset the world restarted leaves the step as reset_worlds leaves one: marked, its sensors at 0
TEST(DivergenceGuard, AWorldTheGuardResetsIsMarkedAsResetAndItsSensorsRead0) {
  ModelBuilder robot = pendulum(), worlds;
  robot.add_sensor(SensorType::JointVel, 0);  // (its hinge)
  worlds.replicate(robot, 4);
  SolverFeatherstoneSettings settings;
  settings.on_divergence = DivergencePolicy::Reset;
  Scene wild(worlds, settings);
  wild.run(0.1);
  wild.state.joint_qd[2] = 2e6;
  wild.run(kDt);
  EXPECT_EQ(wild.solver.diverged(), (std::vector<std::uint8_t>{0, 0, 1, 0}));
  EXPECT_EQ(wild.state.world_reset, (std::vector<std::uint8_t>{0, 0, 1, 0}));
  EXPECT_EQ(wild.state.sensor_data[2], 0);
  EXPECT_NE(wild.state.sensor_data[1], 0);  // (the others swing on)
  wild.run(kDt);
  EXPECT_EQ(wild.state.world_reset, (std::vector<std::uint8_t>{0, 0, 0, 0}));
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

// ---- the guard's depth and energy, and the reset state ----

// the quadruped at dt = 1 s falls through the floor in its first step (no contact yet: nothing to see); the next
// step's contacts are metres deep: it diverged, by each policy
TEST(DivergenceGuard, AContactTooDeepMarksItsWorldDiverged) {
  ModelBuilder builder;
  import_mjcf(builder, NOVAPHY_SCENE_DIR "/quadruped.xml");
  builder.add_keyframe("crouch", builder.finalize().joint_q0);
  for (const DivergencePolicy policy : {DivergencePolicy::Raise, DivergencePolicy::Flag, DivergencePolicy::Reset}) {
    SolverFeatherstoneSettings settings;
    settings.on_divergence = policy;
    Scene scene(builder, settings);
    scene.run(1, 1);
    EXPECT_EQ(scene.solver.diverged()[0], 0);
    const State fallen = scene.state;
    scene.pipeline.collide(scene.state, scene.contacts);
    const Scalar deepest = *std::max_element(scene.contacts.contact_depth.begin(),
                                             scene.contacts.contact_depth.begin() + scene.contacts.contact_count);
    ASSERT_GT(deepest, 1);
    if (policy == DivergencePolicy::Raise) {
      std::ostringstream expected;
      expected.precision(17);
      expected << "step diverged in articulation 0: a contact " << deepest
               << " m deep, beyond divergence_depth 0.5 m (the last step's dt too large for the scene?)";
      EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, 1),
                           expected.str());
      EXPECT_EQ(scene.state.joint_q, fallen.joint_q);
      continue;
    }
    scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, 1);
    EXPECT_EQ(scene.solver.diverged()[0], 1);
    EXPECT_EQ(scene.state.joint_q, policy == DivergencePolicy::Flag ? fallen.joint_q : scene.model.joint_q0);
  }
}

// four pendulums; world 2 is driven by a torque that gives it, in one step, far more kinetic energy per kilogram
// than divergence_energy, at a speed below divergence_speed: it alone diverged
TEST(DivergenceGuard, AnEnergyBlowUpMarksItsWorldDiverged) {
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    Scene calm(pendulum_worlds(precision)), wild(pendulum_worlds(precision));
    wild.control.joint_f[2] = 1e6;  // 1e5 rad/s after one step: below 1e6 rad/s, beyond 1e7 J/kg
    calm.run(kDt);
    wild.run(kDt);
    EXPECT_EQ(wild.solver.diverged(), (std::vector<std::uint8_t>{0, 0, 1, 0}));
    EXPECT_EQ(wild.state.joint_qd[2], 0);  // kept as it was
    for (const int w : {0, 1, 3}) EXPECT_EQ(wild.state.joint_qd[w], calm.state.joint_qd[w]);
    wild.solver.settings.divergence_energy = kUnbounded;  // the speed alone passes it
    wild.run(kDt);
    EXPECT_EQ(wild.solver.diverged()[2], 0);
    EXPECT_GT(std::abs(wild.state.joint_qd[2]), 1e4);
    EXPECT_LT(std::abs(wild.state.joint_qd[2]), 1e6);
    EXPECT_GT(0.5 * 0.0842 * wild.state.joint_qd[2] * wild.state.joint_qd[2], 1e7);  // (H_00 / m: 0.0842 m^2)
  }
}

// under Reset a diverged world comes back exactly at the keyframe the user names: its coordinates and velocities
TEST(DivergenceGuard, ResetRestartsFromTheKeyframeTheUserNames) {
  ModelBuilder robot, worlds;
  const int link = robot.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions joint;
  joint.dof.axis = Vec3::UnitZ();
  joint.child_xform.p = Vec3(-0.25, 0, 0);
  robot.add_joint_revolute(-1, link, joint);
  robot.add_keyframe("swing", {0.7}, {-1.5});
  worlds.replicate(robot, 4);
  for (const bool batched : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.on_divergence = DivergencePolicy::Reset;
    settings.use_batch_kernels = batched;
    Scene scene(worlds, settings);
    scene.solver.set_reset_keyframe("swing");
    scene.run(0.5);
    scene.state.joint_qd[2] = 2e6;
    scene.run(kDt);
    EXPECT_EQ(scene.solver.diverged()[2], 1);
    EXPECT_EQ(scene.state.joint_q[2], 0.7);
    EXPECT_EQ(scene.state.joint_qd[2], -1.5);
    const State key = scene.model.state("swing");
    for (int k = 0; k < 7; ++k) EXPECT_EQ(scene.state.body_q[7 * 2 + k], key.body_q[7 * 2 + k]);
    EXPECT_NE(scene.state.joint_q[1], 0.7);  // the others went on swinging
    EXPECT_NOVAPHY_ERROR(scene.solver.set_reset_keyframe("stand"), "stand");
    State bad = scene.model.state();
    bad.joint_qd[3] = std::nan("");
    EXPECT_NOVAPHY_ERROR(scene.solver.set_reset_state(bad), "reset state: joint_qd[3] is not finite: nan");
  }
}

}  // namespace
}  // namespace novaphy
