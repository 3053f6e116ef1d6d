// Fixed tendons (model.h, engine/model/tendon.h): springs, dampers and actuators on tendons against MuJoCo on
// the same MJCF, a tendon joining the articulations of a gripper's fingers, and the joins refused.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <random>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support.h"
#include "test_support_errors.h"
#include "tools/mujoco_oracle.h"

namespace novaphy {
namespace {

// two fingers on slides and a hinge, coupled by fixed tendons with springs and dampers (one at its own
// spring length, one at its length at qpos0), driven by a motor, a position servo and a general actuator
// on the tendons beside a position servo on a joint
constexpr const char* kTendonHand = R"(
<mujoco model="tendon hand">
  <option gravity="0 0 -9.81" timestep="0.002"/>
  <worldbody>
    <body name="palm" pos="0 0 1">
      <joint name="wrist" type="hinge" axis="0 1 0" damping="0.05"/>
      <geom type="box" size="0.05 0.05 0.02" mass="0.5"/>
      <body name="left" pos="0 0.03 -0.05">
        <joint name="left_slide" type="slide" axis="0 1 0"/>
        <geom type="box" size="0.01 0.01 0.03" mass="0.05"/>
      </body>
      <body name="right" pos="0 -0.03 -0.05">
        <joint name="right_slide" type="slide" axis="0 -1 0"/>
        <geom type="box" size="0.01 0.01 0.03" mass="0.05"/>
        <body name="tip" pos="0 0 -0.04">
          <joint name="tip_hinge" type="hinge" axis="1 0 0"/>
          <geom type="sphere" size="0.01" mass="0.02"/>
        </body>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="grip" stiffness="20" damping="0.5" springlength="0.01">
      <joint joint="left_slide" coef="0.5"/>
      <joint joint="right_slide" coef="0.5"/>
    </fixed>
    <fixed name="curl" stiffness="3" damping="0.1">
      <joint joint="right_slide" coef="2"/>
      <joint joint="tip_hinge" coef="-0.3"/>
      <joint joint="wrist" coef="0.2"/>
    </fixed>
  </tendon>
  <actuator>
    <motor name="squeeze" tendon="grip" gear="3" ctrllimited="true" ctrlrange="-1 1"/>
    <position name="curl_servo" tendon="curl" kp="8" kv="0.4"/>
    <general name="grip_general" tendon="grip" gainprm="2" biastype="affine" biasprm="0.1 -5 -0.3" gear="0.7"/>
    <position name="wrist_servo" joint="wrist" kp="4"/>
  </actuator>
</mujoco>)";

TEST(Tendons, SpringsDampersAndActuatorsMatchMujocosForwardDynamics) {
  const std::string path = test::write_temp_file("tendon_hand.xml", kTendonHand);
  MujocoOracle oracle(path);
  ASSERT_EQ(oracle.model().tendon_count, 2);
  ASSERT_EQ(oracle.model().actuator_count, 4);
  EXPECT_TRUE(oracle.import().warnings.empty()) << oracle.import().warnings[0];
  std::mt19937 rng(5);
  OracleErrors worst;
  for (int k = 0; k < 40; ++k) worst.accumulate(oracle.compare_random_state(rng));
  EXPECT_LT(worst.bias, 1e-9);
  EXPECT_LT(worst.qdd_crba, 1e-9);
  EXPECT_LT(worst.qdd_aba, 1e-9);
  EXPECT_LT(worst.qdd_batched, 1e-9);
  std::filesystem::remove(path);
}

// a parallel gripper as Menagerie's Franka hand (tests/python/models/gripper.xml)
const std::string kGripper = NOVAPHY_TEST_MODEL_DIR "/gripper.xml";

TEST(Tendons, ATendonJoinsAGrippersFingersIntoOneArticulationAndMovesThemAsMujoco) {
  MujocoOracle oracle(kGripper);
  const Model& model = oracle.model();
  ASSERT_EQ(model.articulation_count, 1);
  EXPECT_TRUE(oracle.import().warnings.empty()) << oracle.import().warnings[0];
  std::mt19937 rng(3);
  OracleErrors worst;
  for (int k = 0; k < 20; ++k) worst.accumulate(oracle.compare_random_state(rng));
  EXPECT_LT(worst.max(), 1e-9);

  // the servo opens the fingers against the tendon's range, on both routes, as MuJoCo 2.2.2 does
  mjModel* m = load_mujoco_model(kGripper);
  mjData* d = mj_makeData(m);
  d->ctrl[0] = 255;
  for (int k = 0; k < 500; ++k) mj_step(m, d);
  Control control = model.control();
  control.actuator_ctrl[0] = 255;
  for (const bool blocks : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = blocks;
    const State s = test::run_steps(model, control, 500, 0.002, settings);
    const std::string route = blocks ? "blocks" : "dense";
    EXPECT_NEAR(0.5 * (s.joint_q[0] + s.joint_q[1]), 0.03, 2e-3) << route;
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(s.joint_q[k], d->qpos[k], 1e-3) << route << " finger " << k;
  }
  mj_deleteData(d);
  mj_deleteModel(m);
}

TEST(Tendons, EachWorldOfABatchOfGrippersStepsAsItDoesAlone) {
  // the joined articulation (two roots) in the SIMD blocks: 7 worlds, each with its own command
  constexpr int kWorlds = 7;
  ModelBuilder gripper;
  gripper.add_mjcf(kGripper);
  ModelBuilder batch(gripper.gravity());
  batch.replicate(gripper, kWorlds);
  const Model many = batch.finalize(), alone = gripper.finalize();
  ASSERT_EQ(many.articulation_count, kWorlds);
  Control control = many.control();
  for (int w = 0; w < kWorlds; ++w) control.actuator_ctrl[w] = 40 * w;
  const State stepped = test::run_steps(many, control, 300, 0.002);
  for (int w = 0; w < kWorlds; ++w) {
    Control c = alone.control();
    c.actuator_ctrl[0] = 40 * w;
    const State s = test::run_steps(alone, c, 300, 0.002);
    ASSERT_EQ(std::memcmp(&stepped.joint_q[2 * w], s.joint_q.data(), 2 * sizeof(Scalar)), 0) << "world " << w;
    ASSERT_EQ(std::memcmp(&stepped.joint_qd[2 * w], s.joint_qd.data(), 2 * sizeof(Scalar)), 0) << "world " << w;
  }
}

TEST(Tendons, ArticulationsATendonCannotJoinAreNamed) {
  const RigidBody link = RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1));
  JointOptions hinge;
  hinge.dof.axis = Vec3::UnitZ();
  {  // a floating robot's joint and a fixed one's
    ModelBuilder builder;
    const int base = builder.add_body(link);
    builder.add_joint_free(-1, base);
    const int arm = builder.add_joint_revolute(base, builder.add_body(link), hinge);
    const int post = builder.add_joint_revolute(-1, builder.add_body(link), hinge);
    builder.add_tendon({arm, post}, {1, 1}, {.name = "reach"});
    EXPECT_NOVAPHY_ERROR(builder.finalize(),
                         "tendon 0 ('reach'): its joints 1 and 2 are in different articulations, one of them "
                         "floating (a tendon joins articulations of fixed base only)");
  }
  {  // an articulation given by add_articulation
    ModelBuilder builder;
    const int a = builder.add_joint_revolute(-1, builder.add_body(link), hinge);
    const int b = builder.add_joint_revolute(-1, builder.add_body(link), hinge);
    builder.add_articulation({a});
    builder.add_tendon({a, b}, {1, -1});
    EXPECT_NOVAPHY_ERROR(builder.finalize(),
                         "tendon 0: its joints 0 and 1 are in different articulations, one given by add_articulation");
  }
  {  // two articulations with a third between them in joint order
    ModelBuilder builder;
    int joints[3];
    for (int& j : joints) j = builder.add_joint_revolute(-1, builder.add_body(link), hinge);
    builder.add_tendon({joints[0], joints[2]}, {1, 1}, {.name = "around"});
    EXPECT_NOVAPHY_ERROR(builder.finalize(),
                         "tendon 0 ('around'): joins articulations whose joints are not one after another");
  }
}

}  // namespace
}  // namespace novaphy
