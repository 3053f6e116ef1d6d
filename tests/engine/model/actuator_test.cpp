// MuJoCo's affine actuators (engine/model/actuator.h): every kind against MuJoCo on the same MJCF, a stiff
// position servo stable at a large step (its gains taken implicitly), a clamped actuator exact at its limit,
// per-world gains with each world stepping as it does alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support.h"
#include "tools/mujoco_oracle.h"

namespace novaphy {
namespace {

// an arm of hinges and a slide driven by a motor, position and velocity servos and a general actuator of
// affine bias (two on one joint), some with control and force ranges
constexpr const char* kActuatedArm = R"(
<mujoco model="actuated arm">
  <option gravity="0 0 -9.81" timestep="0.002"/>
  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="yaw" type="hinge" axis="0 0 1" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04" mass="1"/>
      <body name="upper" pos="0.3 0 0">
        <joint name="pitch" type="hinge" axis="0 1 0" armature="0.01"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.7"/>
        <body name="slider" pos="0.3 0 0">
          <joint name="extend" type="slide" axis="1 0 0"/>
          <geom type="box" size="0.05 0.05 0.05" mass="0.3"/>
          <body name="wrist" pos="0.1 0 0">
            <joint name="roll" type="hinge" axis="1 0 0"/>
            <geom type="sphere" size="0.04" mass="0.2" pos="0 0.05 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="yaw_motor" joint="yaw" gear="2" ctrllimited="true" ctrlrange="-1 1"/>
    <position name="yaw_servo" joint="yaw" kp="5"/>
    <position name="pitch_servo" joint="pitch" kp="30" ctrllimited="true" ctrlrange="-0.8 0.8"
              forcelimited="true" forcerange="-5 5"/>
    <velocity name="extend_servo" joint="extend" kv="4" gear="1.5"/>
    <general name="roll_general" joint="roll" gainprm="3" biastype="affine" biasprm="0.2 -2 -0.5" gear="0.8"/>
  </actuator>
</mujoco>)";

TEST(Actuators, EveryKindMatchesMujocosForwardDynamics) {
  const std::string path = test::write_temp_file("actuated_arm.xml", kActuatedArm);
  MujocoOracle oracle(path);
  ASSERT_EQ(oracle.model().actuator_count, 5);
  std::mt19937 rng(3);
  OracleErrors worst;
  for (int k = 0; k < 40; ++k) worst.accumulate(oracle.compare_random_state(rng));
  EXPECT_LT(worst.qdd_crba, 1e-9);
  EXPECT_LT(worst.qdd_aba, 1e-9);
  EXPECT_LT(worst.qdd_batched, 1e-9);
  std::filesystem::remove(path);
}

// a light link on a hinge (zero gravity), its servo's gain far beyond what an explicit step survives
Model servo_link(Scalar kp, Scalar kv, Scalar force_limit, int worlds = 1, Precision precision = Precision::Float64) {
  ModelBuilder robot(Vec3::Zero());
  const int link = robot.add_body(RigidBody::from_box(0.1, Vec3(0.1, 0.02, 0.02)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.1, 0, 0);
  const int joint = robot.add_joint_revolute(-1, link, options);
  ActuatorOptions limits;
  limits.force_lower = -force_limit;
  limits.force_upper = force_limit;
  robot.add_position(joint, kp, kv, limits);
  ModelBuilder batch(Vec3::Zero());
  batch.set_precision(precision);
  batch.replicate(robot, worlds);
  return batch.finalize();
}

TEST(Actuators, AStiffPositionServoHoldsItsTargetAtALargeStep) {
  // kp 1e4 on a link of 1.3e-3 kg m^2 about its hinge: omega dt = 46 at dt = 1/60 s, where an explicit step
  // diverges; taken implicitly the servo settles on its target, on the blocks and on the dense route
  const Model model = servo_link(1e4, 5, std::numeric_limits<Scalar>::infinity());
  Control control = model.control();
  control.actuator_ctrl[0] = 0.7;
  for (const bool blocks : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = blocks;
    settings.angular_damping = 0;
    EXPECT_NEAR(test::run_steps(model, control, 180, 1.0 / 60, settings).joint_q[0], 0.7, 1e-6)
        << (blocks ? "blocks" : "dense");
  }
}

TEST(Actuators, AClampedActuatorIsExactAtItsLimit) {
  // the servo far from its target pushes with its force limit, no more: one step from rest gives
  // qd = dt limit / I exactly (I from the mass matrix), on the dense route in double
  const Model model = servo_link(1e4, 5, 0.25);
  State state = model.state();
  Control control = model.control();
  control.actuator_ctrl[0] = 2;
  const VecX tau = eval_control_force(model, control, &state);
  EXPECT_EQ(tau[0], 0.25);
  SolverFeatherstoneSettings settings;
  settings.use_batch_kernels = false;
  settings.angular_damping = 0;
  SolverFeatherstone solver(model, settings);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  const Scalar inertia = eval_mass_matrix(model, state)(0, 0), dt = 0.01;
  solver.step(state, state, control, contacts, dt);
  EXPECT_NEAR(state.joint_qd[0], dt * 0.25 / inertia, 1e-15);
}

TEST(Actuators, PerWorldGainsAndEachWorldStepsAsItDoesAlone) {
  // every world its own kp, kv and force limit, and its own target; each world of the batch equals itself
  // stepped alone, bit for bit, in both precisions
  constexpr int kWorlds = 37;
  auto randomize = [](Model& model, Control& control, int w, int u) {
    model.actuator_gain[u] = 50 + 10 * w;
    model.actuator_bias[3 * u + 1] = -model.actuator_gain[u];
    model.actuator_bias[3 * u + 2] = -(0.5 + 0.1 * w);
    model.actuator_force_upper[u] = 1 + 0.3 * w;
    model.actuator_force_lower[u] = -model.actuator_force_upper[u];
    control.actuator_ctrl[u] = std::sin(0.7 * w);
  };
  auto run = [](const Model& model, const Control& control) { return test::run_steps(model, control, 100, 0.01); };
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    Model batch = servo_link(1, 0, 1, kWorlds, precision);
    Control control = batch.control();
    for (int w = 0; w < kWorlds; ++w) randomize(batch, control, w, w);
    const State stepped = run(batch, control);
    for (int w = 0; w < kWorlds; ++w) {
      Model alone = servo_link(1, 0, 1, 1, precision);
      Control alone_control = alone.control();
      randomize(alone, alone_control, w, 0);
      const State s = run(alone, alone_control);
      ASSERT_EQ(std::memcmp(&stepped.joint_q[w], s.joint_q.data(), sizeof(Scalar)), 0) << "world " << w;
      ASSERT_EQ(std::memcmp(&stepped.joint_qd[w], s.joint_qd.data(), sizeof(Scalar)), 0) << "world " << w;
    }
    EXPECT_NE(stepped.joint_q[0], stepped.joint_q[5]);  // the worlds differ
  }
}

}  // namespace
}  // namespace novaphy
