// Fixed tendons (model.h, engine/parts/tendon.h): springs, dampers and actuators on tendons against MuJoCo on
// the same MJCF, their limits as rows of the step, each world of a batch as it steps alone, and bad input.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <random>

#include "engine/dynamics.h"
#include "engine/mjcf_import.h"
#include "engine/solver_featherstone.h"
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

}  // namespace
}  // namespace novaphy
