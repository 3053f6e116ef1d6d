// Keyframes (Model::state(name), Model::control(name)): imported from MJCF and converted (quaternion order,
// the Free joint's velocity), every world of a replicated model at its keyframe, and bad names named.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <filesystem>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

// a floating base with a hinge, a slide and a ball, driven by a servo and a motor; two keyframes
constexpr const char* kKeyed = R"(
<mujoco model="keyed">
  <worldbody>
    <body name="base" pos="0 0 1">
      <freejoint name="root"/>
      <geom type="box" size="0.2 0.1 0.05" mass="2"/>
      <body name="arm" pos="0.2 0 0">
        <joint name="hinge" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.03" mass="0.5"/>
        <body name="slider" pos="0.2 0 0">
          <joint name="slide" type="slide" axis="1 0 0"/>
          <geom type="sphere" size="0.04" mass="0.2"/>
          <body name="head" pos="0.05 0 0">
            <joint name="ball" type="ball"/>
            <geom type="box" size="0.03 0.03 0.03" mass="0.1"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="servo" joint="hinge" kp="20"/>
    <motor name="push" joint="slide"/>
  </actuator>
  <keyframe>
    <key name="home" qpos="0.1 -0.2 0.8  0.9238795 0 0.3826834 0  0.5  0.05  0.7071068 0.7071068 0 0"
         qvel="0.1 0.2 0.3  1 -1 0.5  0.2  -0.1  0.3 0 0" ctrl="0.4 -1.5"/>
    <key name="folded" qpos="0 0 0.5  1 0 0 0  -1  0  1 0 0 0"/>
  </keyframe>
</mujoco>)";

TEST(Keyframes, EveryWorldStartsAtTheImportedKeyframeWhereMujocoPutsIt) {
  const std::string path = test::write_temp_file("keyed.xml", kKeyed);
  ModelBuilder robot(Vec3(0, 0, -9.81));
  robot.add_mjcf(path);
  ModelBuilder worlds(robot.gravity());
  worlds.replicate(robot, 3, Vec3(2, 0, 0));
  const Model model = worlds.finalize();
  ASSERT_EQ(model.keyframe_name, (std::vector<std::string>{"home", "folded"}));

  // MuJoCo's own poses of the keyframe's bodies
  char error[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  mj_resetDataKeyframe(m, d, 0);
  mj_forward(m, d);
  const State state = model.state("home");
  const Control control = model.control("home");
  const int bodies = model.body_count / 3, nq = model.joint_coord_count / 3, nu = model.actuator_count / 3;
  for (int w = 0; w < 3; ++w) {
    for (int b = 1; b < m->nbody; ++b) {
      const Scalar* q = &state.body_q[7 * (w * bodies + b - 1)];
      EXPECT_NEAR(q[0], d->xpos[3 * b] + 2 * w, 1e-12) << "world " << w << " body " << b;
      EXPECT_NEAR(q[1], d->xpos[3 * b + 1], 1e-12);
      EXPECT_NEAR(q[2], d->xpos[3 * b + 2], 1e-12);
      const Scalar sign = q[6] * d->xquat[4 * b] < 0 ? -1 : 1;  // q and -q are one rotation
      EXPECT_NEAR(q[6], sign * d->xquat[4 * b], 1e-12);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(q[3 + k], sign * d->xquat[4 * b + 1 + k], 1e-12);
    }
    // the Free joint's velocity converted: [w_world; v] from MuJoCo's [v; w_body]
    const Vec3 w_world = Eigen::Map<const Vec3>(&state.joint_qd[w * model.joint_dof_count / 3]);
    Eigen::Matrix3d R;
    mju_quat2Mat(R.data(), m->key_qpos + 3);
    EXPECT_LT((w_world - R.transpose() * Vec3(1, -1, 0.5)).norm(), 1e-12);  // (row-major read: R^T is R)
    EXPECT_EQ(state.joint_q[w * nq + 7], 0.5);                              // the hinge
    EXPECT_EQ(control.actuator_ctrl[w * nu], 0.4);
    EXPECT_EQ(control.actuator_ctrl[w * nu + 1], -1.5);
  }
  // a keyframe without qvel and ctrl: at rest, commands zero
  const State folded = model.state("folded");
  for (const Scalar v : folded.joint_qd) EXPECT_EQ(v, 0);
  EXPECT_EQ(folded.joint_q[7], -1);
  for (const Scalar u : model.control("folded").actuator_ctrl) EXPECT_EQ(u, 0);
  mj_deleteData(d);
  mj_deleteModel(m);
  std::filesystem::remove(path);
}

TEST(Keyframes, AMissingNameListsTheModelsKeyframes) {
  const std::string path = test::write_temp_file("keyed_names.xml", kKeyed);
  ModelBuilder robot;
  robot.add_mjcf(path);
  const Model model = robot.finalize();
  EXPECT_NOVAPHY_ERROR(model.state("stand"), "no keyframe 'stand': the model has 'home', 'folded'");
  EXPECT_NOVAPHY_ERROR(model.control("stand"), "no keyframe 'stand'");
  EXPECT_NOVAPHY_ERROR(ModelBuilder().finalize().state("home"), "no keyframe 'home': the model has none");
  std::filesystem::remove(path);
}

TEST(Keyframes, BuilderKeyframesAreCheckedAndMerged) {
  ModelBuilder builder(Vec3::Zero());
  const int body = builder.add_body(RigidBody::from_sphere(1, 0.1));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  const int hinge = builder.add_joint_revolute(-1, body, options);
  builder.add_motor(hinge);
  EXPECT_NOVAPHY_ERROR(builder.add_keyframe("k", {0.1, 0.2}), "keyframe 'k': joint_q has 2 entries");
  EXPECT_NOVAPHY_ERROR(builder.add_keyframe("k", {std::nan("")}), "keyframe 'k': joint_q[0] is not finite");
  EXPECT_NOVAPHY_ERROR(builder.add_keyframe("k", {0.1}, {}, {1, 2}), "keyframe 'k': ctrl has 2 entries");
  builder.add_keyframe("k", {0.3}, {0.5}, {0.7});
  ModelBuilder two(Vec3::Zero());
  two.replicate(builder, 2);
  const int loose = two.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0, 0, 3)});  // no keyframe names it
  const Model model = two.finalize();
  const State state = model.state("k");
  EXPECT_EQ(state.joint_q[0], 0.3);
  EXPECT_EQ(state.joint_q[1], 0.3);
  EXPECT_EQ(state.joint_qd[1], 0.5);
  EXPECT_EQ(state.joint_q[2 + 2], 3);  // the loose body's Free joint keeps its initial pose
  EXPECT_EQ(model.control("k").actuator_ctrl[1], 0.7);
  EXPECT_EQ(loose, 2);
}

}  // namespace
}  // namespace novaphy
