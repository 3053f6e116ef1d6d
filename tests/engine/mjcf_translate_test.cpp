// MuJoCo >= 3 MJCF through MuJoCo 2.2.2's parser (engine/mjcf_translate.h): the translations, through an
// <include>, give the model MuJoCo 3 would compile; an attribute without one is named with its file and line.
#include "engine/mjcf_translate.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "engine/mjcf_import.h"
#include "test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

TEST(MjcfTranslate, MujocoThreeSyntaxLoadsAsMujocoThreeMeansIt) {
  // implicitfast, a range without `limited` (autolimits by default), a servo's kv on the element and from its
  // class, a keyframe over several lines, all in an included file
  const std::string included = test::write_temp_file("three_robot.xml", R"(
<mujoco>
  <compiler angle="radian"/>
  <option integrator="implicitfast"/>
  <default>
    <default class="servo"><position kp="40" kv="3"/></default>
  </default>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="fore" pos="0.3 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="own" joint="shoulder" kp="25" kv="2"/>
    <position name="classed" class="servo" joint="elbow"/>
  </actuator>
  <keyframe>
    <key name="home"
         qpos="0.3
               -0.4"/>
  </keyframe>
</mujoco>)");
  const std::string main = test::write_temp_file(
      "three_scene.xml",
      "<mujoco><include file=\"" + std::filesystem::path(included).filename().string() + "\"/></mujoco>");
  ModelBuilder builder;
  builder.add_mjcf(main);
  const Model model = builder.finalize();
  ASSERT_EQ(model.actuator_count, 2);
  EXPECT_EQ(model.actuator_gain[0], 25);
  EXPECT_EQ(model.actuator_bias[1], -25);
  EXPECT_EQ(model.actuator_bias[2], -2);
  EXPECT_EQ(model.actuator_gain[1], 40);
  EXPECT_EQ(model.actuator_bias[4], -40);
  EXPECT_EQ(model.actuator_bias[5], -3);
  EXPECT_EQ(model.joint_limit_lower[0], -1);  // autolimits: the range limits the joint
  EXPECT_EQ(model.joint_limit_upper[0], 1);
  const State home = model.state("home");
  EXPECT_EQ(home.joint_q[0], 0.3);
  EXPECT_EQ(home.joint_q[1], -0.4);
  mjModel* m = load_mujoco_model(main);
  EXPECT_EQ(m->opt.integrator, mjINT_IMPLICIT);
  mj_deleteModel(m);
  std::filesystem::remove(included);
  std::filesystem::remove(main);
}

TEST(MjcfTranslate, AnAttributeWithoutATranslationIsNamedWithItsFileAndLine) {
  const std::string path = test::write_temp_file("three_dampratio.xml", R"(<mujoco>
  <worldbody><body><joint name="j" type="hinge"/><geom type="sphere" size="0.1"/></body></worldbody>
  <actuator><position joint="j" kp="10" dampratio="1"/></actuator>
</mujoco>)");
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(path),
                       "three_dampratio.xml line 3: <position>: MuJoCo 3's attribute 'dampratio' has no translation");
  std::filesystem::remove(path);
}

TEST(MjcfTranslate, AFileThatIsNotXmlIsLeftToMujocosParser) {
  const std::string path = test::write_temp_file("three_broken.xml", "<mujoco><worldbody></mujoco>");
  EXPECT_EQ(translate_mjcf(path).vfs, nullptr);
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(path), "XML parse error");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace novaphy
