// MuJoCo >= 3 MJCF through MuJoCo 2.2.2's parser (engine/import/mjcf_translate.h): the translations, through an
// <include>, give the model MuJoCo 3 would compile; an attribute without one is named with its file and line.
#include "engine/import/mjcf_translate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
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

TEST(MjcfTranslate, ADampingRatioGivesTodaysMujocosKvFromTheInertiaAtQpos0) {
  // kv = 2 dampratio sqrt(kp m), m = 1 / (J M^-1 J^T) at qpos0 (armature included), J the joint's gear:
  // NovaPhy's own mass matrix at the initial coordinates is the oracle
  const std::string path = test::write_temp_file("three_dampratio.xml", R"(<mujoco>
  <default><default class="critical"><position kp="30" dampratio="1"/></default></default>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" armature="0.02"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="fore" pos="0.3 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" ref="0.4"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position joint="shoulder" kp="10" dampratio="0.5" gear="2"/>
    <position joint="elbow" class="critical"/>
  </actuator>
</mujoco>)");
  ModelBuilder builder;
  ASSERT_TRUE(builder.add_mjcf(path).empty());
  const Model model = builder.finalize();
  EXPECT_EQ(model.joint_q0[1], 0.4 * M_PI / 180);  // the model starts at MuJoCo's qpos0: ref, in degrees
  const MatX H_inverse = eval_mass_matrix(model, model.state()).inverse();
  EXPECT_NEAR(model.actuator_bias[2], -2 * 0.5 * std::sqrt(10 / (4 * H_inverse(0, 0))), 1e-12);
  EXPECT_NEAR(model.actuator_bias[5], -2 * 1.0 * std::sqrt(30 / H_inverse(1, 1)), 1e-12);
  EXPECT_EQ(model.actuator_bias[4], -30);
  std::filesystem::remove(path);
}

TEST(MjcfTranslate, AJointsActuatorForceRangeAndAServosInheritedRange) {
  // actuatorfrcrange from a class through a body's childclass, over the gear of the joint's one actuator;
  // inheritrange scaling the joint's range about its middle; a joint with two actuators cannot be translated
  auto file = [](const std::string& second_actuator) {
    return R"(<mujoco>
  <compiler angle="radian"/>
  <default><default class="leg"><joint actuatorfrcrange="-6 4" range="-0.5 1.5"/></default></default>
  <worldbody>
    <body name="hip" pos="0 0 1" childclass="leg">
      <joint name="swing" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="shin" pos="0.3 0 0">
        <joint name="knee" type="hinge" axis="0 1 0" actuatorfrclimited="false"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="swing_servo" joint="swing" kp="10" gear="2" inheritrange="0.5" forcelimited="true"
              forcerange="-1 5"/>
    <position name="knee_servo" joint="knee" kp="10"/>)" +
           second_actuator + R"(
  </actuator>
</mujoco>)";
  };
  const std::string path = test::write_temp_file("three_ranges.xml", file(""));
  ModelBuilder builder;
  ASSERT_TRUE(builder.add_mjcf(path).empty());
  const Model model = builder.finalize();
  EXPECT_EQ(model.actuator_force_lower[0], -1);         // its own range is narrower below
  EXPECT_EQ(model.actuator_force_upper[0], 2);          // 4 / gear
  EXPECT_NEAR(model.actuator_ctrl_lower[0], 0, 1e-15);  // 0.5 -+ 0.5 * 1
  EXPECT_NEAR(model.actuator_ctrl_upper[0], 1, 1e-15);
  EXPECT_TRUE(std::isinf(model.actuator_force_upper[1]));  // actuatorfrclimited="false"
  const std::string two = test::write_temp_file("three_two.xml", file(R"(<motor joint="swing"/>)"));
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(two),
                       "joint 'swing': actuatorfrcrange with 2 actuators on it has no MuJoCo 2.2.2 equivalent");
  std::filesystem::remove(path);
  std::filesystem::remove(two);
}

// a compiler's assetdir becomes its meshdir and texturedir (its own meshdir kept), the viewer's ellipsoidinertia
// is dropped: the translation says so, and the file loads
TEST(MjcfTranslate, AssetdirAndTheViewersEllipsoidinertia) {
  const std::string path = test::write_temp_file("three_assetdir.xml", R"(<mujoco>
  <compiler assetdir="assets" meshdir="meshes"/>
  <visual><global ellipsoidinertia="true"/></visual>
  <worldbody><body><joint type="hinge"/><geom type="sphere" size="0.1"/></body></worldbody>
</mujoco>)");
  const TranslatedMjcf translated = translate_mjcf(path);
  const auto said = [&](const std::string& what) {
    return std::any_of(translated.translations.begin(), translated.translations.end(),
                       [&](const std::string& t) { return t.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(said("assetdir=\"assets\" -> meshdir and texturedir"));
  EXPECT_TRUE(said("ellipsoidinertia (how the viewer draws inertias, no physics) -> dropped"));
  ModelBuilder builder;
  builder.add_mjcf(path);
  EXPECT_EQ(builder.finalize().joint_count, 1);
  std::filesystem::remove(path);
}

TEST(MjcfTranslate, AnAttributeWithoutATranslationIsNamedWithItsFileAndLine) {
  const std::string path = test::write_temp_file("three_actuatorgravcomp.xml", R"(<mujoco>
  <worldbody><body><joint name="j" type="hinge" actuatorgravcomp="true"/><geom type="sphere" size="0.1"/></body>
  </worldbody>
</mujoco>)");
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(
      builder.add_mjcf(path),
      "three_actuatorgravcomp.xml line 2: <joint>: MuJoCo 3's attribute 'actuatorgravcomp' has no translation");
  std::filesystem::remove(path);
}

// a body's gravcomp is taken out and set on the compiled body (by name: an unnamed one is an error)
TEST(MjcfTranslate, GravcompIsSetOnTheNamedBody) {
  const std::string path = test::write_temp_file("three_gravcomp.xml", R"(<mujoco>
  <worldbody><body name="arm" gravcomp="0.75"><joint type="hinge"/><geom type="sphere" size="0.1"/>
    <body name="hand" pos="0.2 0 0"><joint type="hinge"/><geom type="sphere" size="0.1"/></body></body>
  </worldbody>
</mujoco>)");
  ModelBuilder builder;
  builder.add_mjcf(path);
  const Model model = builder.finalize();
  EXPECT_EQ(model.body_gravcomp, (std::vector<Scalar>{0.75, 0}));
  const std::string unnamed = test::write_temp_file("three_unnamed.xml", R"(<mujoco>
  <worldbody><body gravcomp="1"><joint type="hinge"/><geom type="sphere" size="0.1"/></body></worldbody>
</mujoco>)");
  EXPECT_NOVAPHY_ERROR(ModelBuilder().add_mjcf(unnamed),
                       "three_unnamed.xml line 2: <body>: MuJoCo 3's 'gravcomp' is applied after compiling, by name: "
                       "name the <body>");
  std::filesystem::remove(path);
  std::filesystem::remove(unnamed);
}

TEST(MjcfTranslate, AFileThatIsNotXmlOrADirectoryIsNamedInWords) {
  const std::string broken = test::write_temp_file("three_broken.xml", "<mujoco><worldbody></mujoco>");
  const std::string text = test::write_temp_file("three_text.xml", "hello, not a model");
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(
      builder.add_mjcf(broken),
      "three_broken.xml': XML parse error at line 1: a closing tag that does not match the element it closes");
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(text),
                       "three_text.xml': XML parse error at line 1: text outside any element (not an XML file?)");
  const std::string dir = std::filesystem::path(broken).parent_path().string();
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(dir), "cannot load '" + dir + "': a directory, not a file");
  try {
    builder.add_mjcf(text);
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find("XML_ERROR"), std::string::npos) << e.what();
  }
  std::filesystem::remove(broken);
  std::filesystem::remove(text);
}

// the translated file keeps each element on its line, so MuJoCo's parser and compiler name the file's own lines
TEST(MjcfTranslate, MujocosMessagesGiveTheFilesOwnLines) {
  const std::string path = test::write_temp_file("three_lines.xml", R"(<mujoco>
  <worldbody>
    <body name="b">
      <joint name="j" type="hinge"/>

      <geom type="capsule" size="0.1"/>
      <unknownthing/>
    </body>
  </worldbody>
</mujoco>)");
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(path), "Element 'unknownthing', line 7");
  std::filesystem::remove(path);
}

// MuJoCo 2.2.2 reads "nan 0 1" as 0 0 0 and a NaN mass as none given (MuJoCo 4 keeps both): each number that
// 2.2.2 would misread is named as the file wrote it, with its element, attribute, file and line
TEST(MjcfTranslate, ANanAnInfinityOrAZeroQuaternionIsNamedAsTheFileWroteIt) {
  const auto load = [](const std::string& body, const std::string& rest = "") {
    const std::string path = test::write_temp_file(
        "three_numbers.xml", "<mujoco><worldbody>\n" + body + "\n</worldbody>" + rest + "</mujoco>");
    ModelBuilder builder;
    builder.add_mjcf(path);
    std::filesystem::remove(path);
    return builder;
  };
  const std::string joint = R"(<joint name="j" type="hinge"/><geom size="0.1"/>)";
  EXPECT_NOVAPHY_ERROR(load(R"(<body name="b" pos="nan 0 1">)" + joint + "</body>"),
                       R"(three_numbers.xml line 2: <body name="b"> pos="nan 0 1": 'nan' is not a number (NaN))");
  EXPECT_NOVAPHY_ERROR(load(R"(<body pos="0 0 1"><joint axis="INF 0 0"/><geom size="0.1"/></body>)"),
                       R"(line 2: <joint> axis="INF 0 0": 'INF' is infinite (only a range's bounds may be))");
  EXPECT_NOVAPHY_ERROR(load(R"(<body name="b" quat="0 0 0 0">)" + joint + "</body>"),
                       R"(line 2: <body name="b"> quat="0 0 0 0": a zero quaternion)");
  // 2.2.2 compiles an inertial frame's zero quaternion into a body without inertia (a massless link when stepped)
  EXPECT_NOVAPHY_ERROR(
      load(R"(<body><joint/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1" quat="0 0 0 0"/></body>)"),
      R"(line 2: <inertial> quat="0 0 0 0": a zero quaternion)");
  EXPECT_NOVAPHY_ERROR(load(R"(<body name="b">)" + joint + "</body>",
                            R"(<keyframe><key name="rest"/><key name="home" qpos="-nan"/></keyframe>)"),
                       R"(<key name="home"> (key 1 of the file) qpos="-nan": '-nan' is not a number (NaN))");
  // infinite bounds of a range load as MuJoCo reads them; a body may be named "inf"
  const Model model =
      load(
          R"(<body name="inf"><joint name="j" type="hinge" range="-inf inf" limited="true"/><geom size="0.1"/></body>)",
          R"(<actuator><motor joint="j" ctrlrange="-1 inf" ctrllimited="true"/></actuator>)")
          .finalize();
  EXPECT_EQ(model.body_name[0], "inf");
  EXPECT_EQ(model.joint_limit_upper[0], std::numeric_limits<Scalar>::infinity());
  EXPECT_EQ(model.actuator_ctrl_upper[0], std::numeric_limits<Scalar>::infinity());
}

}  // namespace
}  // namespace novaphy
