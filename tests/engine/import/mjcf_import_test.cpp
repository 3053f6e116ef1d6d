#include "engine/import/mjcf_import.h"

#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>

#include "engine/model/error.h"
#include "test_support.h"
#include "test_support_errors.h"
#include "tools/mujoco_oracle.h"

namespace novaphy {
namespace {

constexpr Scalar kTolerance = 1e-9;
constexpr int kStates = 50;

void expect_matches_mujoco(const std::string& path, unsigned seed) {
  MujocoOracle oracle(path);
  std::mt19937 rng(seed);
  OracleErrors worst;
  for (int k = 0; k < kStates; ++k) worst.accumulate(oracle.compare_random_state(rng));
  EXPECT_LT(worst.body_pose, kTolerance) << path;
  EXPECT_LT(worst.body_velocity, kTolerance) << path;
  EXPECT_LT(worst.mass_matrix, kTolerance) << path;
  EXPECT_LT(worst.bias, kTolerance) << path;
  EXPECT_LT(worst.qdd_crba, kTolerance) << path;
  EXPECT_LT(worst.qdd_aba, kTolerance) << path;
  EXPECT_LT(worst.qdd_batched, kTolerance) << path;
}

class SceneMatchesMujoco : public ::testing::TestWithParam<std::string> {};

TEST_P(SceneMatchesMujoco, PosesMassMatrixBiasAndAccelerations) {
  const std::string path = GetParam();
  ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing (Debian package libmujoco-samples)";
  expect_matches_mujoco(path, 7);
}

INSTANTIATE_TEST_SUITE_P(Scenes, SceneMatchesMujoco,
                         ::testing::Values(NOVAPHY_SCENE_DIR "/pendulum.xml", NOVAPHY_SCENE_DIR "/chain15.xml",
                                           NOVAPHY_SCENE_DIR "/ball_chain30.xml", NOVAPHY_SCENE_DIR "/quadruped.xml",
                                           NOVAPHY_HUMANOID_XML),
                         [](const auto& info) { return std::filesystem::path(info.param).stem().string(); });

class RandomTreeMatchesMujoco : public ::testing::TestWithParam<int> {};

TEST_P(RandomTreeMatchesMujoco, PosesMassMatrixBiasAndAccelerations) {
  const int seed = GetParam();
  std::mt19937 rng(seed);
  const bool floating = seed % 2 == 0;
  const std::string xml = test::random_tree_mjcf(rng, 3 + seed % 10, floating);
  const std::string path = test::write_temp_file("random_tree_" + std::to_string(seed) + ".xml", xml);
  expect_matches_mujoco(path, seed);
  std::filesystem::remove(path);
}

INSTANTIATE_TEST_SUITE_P(Trees, RandomTreeMatchesMujoco, ::testing::Range(0, 24));

TEST(MjcfImport, HumanoidStructureAndWarnings) {
  ModelBuilder builder;
  const MujocoImport import = import_mjcf(builder, NOVAPHY_HUMANOID_XML);
  const Model model = builder.finalize();
  // 1 free joint + 21 hinges; bodies with several hinges become chains of massless links
  EXPECT_EQ(model.joint_dof_count, 27);
  EXPECT_EQ(model.joint_coord_count, 28);
  EXPECT_EQ(model.articulation_count, 1);
  EXPECT_EQ(model.body_name[import.body_map[1]], "torso");
  // the floor plane is static geometry
  EXPECT_EQ(model.shape_type[0], static_cast<int>(ShapeType::Plane));
  EXPECT_EQ(model.shape_body[0], -1);
  // its 21 motors are imported with their gear and control range, in MuJoCo's order
  ASSERT_EQ(model.actuator_count, 21);
  EXPECT_EQ(model.actuator_name[0], "abdomen_y");
  EXPECT_EQ(model.joint_name[model.actuator_joint[0]], "abdomen_y");
  EXPECT_EQ(model.actuator_gear[5], 120);  // right_hip_y
  EXPECT_EQ(model.actuator_ctrl_lower[0], -1);
  EXPECT_EQ(model.actuator_ctrl_upper[0], 1);
  for (const std::string& w : import.warnings) EXPECT_EQ(w.find("actuator"), std::string::npos) << w;
}

TEST(MjcfImport, ReportsTendonsEqualitiesAndUnsupportedGeomsByName) {
  const std::string path = test::write_temp_file("unmodelled.xml", R"(
<mujoco>
  <asset><hfield name="terrain" nrow="2" ncol="2" size="1 1 0.1 0.1"/></asset>
  <worldbody>
    <geom name="ground" type="hfield" hfield="terrain"/>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0" frictionloss="0.1"/>
      <geom name="can" type="cylinder" size="0.1 0.2"/>
      <site name="top"/>
      <body name="b" pos="0 0 -0.5">
        <site name="bottom"/>
        <joint name="jb" type="ball" limited="true" range="0 0.5"/>
        <geom name="ball" type="ellipsoid" size="0.1 0.2 0.3"/>
      </body>
    </body>
  </worldbody>
  <tendon><spatial name="coupling"><site site="top"/><site site="bottom"/></spatial></tendon>
  <equality><tendon name="lock" tendon1="coupling"/></equality>
  <sensor><jointpos joint="ja"/></sensor>
  <actuator><position name="servo" joint="ja" kp="10"/><motor name="spin" joint="jb" gear="1 0 0"/></actuator>
</mujoco>)");
  ModelBuilder builder;
  const std::vector<std::string> warnings = builder.add_mjcf(path);
  std::string all;
  for (const auto& w : warnings) all += w + "\n";
  EXPECT_EQ(all.find("tendon 'coupling'"), std::string::npos) << all;  // a spatial tendon: modelled
  EXPECT_NE(all.find("equality constraint 'lock'"), std::string::npos) << all;
  EXPECT_NE(all.find("geom 'ground' of type 1 (height field)"), std::string::npos) << all;
  EXPECT_EQ(all.find("geom 'can'"), std::string::npos) << all;  // cylinders and ellipsoids collide
  EXPECT_EQ(all.find("geom 'ball'"), std::string::npos) << all;
  EXPECT_EQ(all.find("frictionloss"), std::string::npos) << all;  // modelled: a friction-loss row
  EXPECT_NE(all.find("joint 'jb': ball joint limit"), std::string::npos) << all;
  EXPECT_EQ(all.find("actuator 'servo'"), std::string::npos) << all;  // a position servo on a hinge: modelled
  EXPECT_NE(all.find("actuator 'spin' drives a ball or free joint"), std::string::npos) << all;
  EXPECT_EQ(all.find("sensor"), std::string::npos) << all;  // sensors do not change the motion
  for (const auto& w : warnings) EXPECT_NE(w.find("(affects motion)"), std::string::npos) << w;
  EXPECT_EQ(builder.actuator_count(), 1);
  EXPECT_EQ(builder.finalize().joint_frictionloss[0], 0.1);
  std::filesystem::remove(path);
}

TEST(MjcfImport, CopiesPlacedByXformWithoutTheirFloor) {
  ModelBuilder builder;
  builder.add_mjcf(NOVAPHY_SCENE_DIR "/quadruped.xml");
  ImportOptions options;
  options.xform.p = Vec3(2, 0, 0);
  options.static_shapes = false;
  const MujocoImport second = import_mjcf(builder, NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  const Model model = builder.finalize();
  EXPECT_EQ(model.articulation_count, 2);
  int planes = 0;
  for (int s = 0; s < model.shape_count; ++s) planes += model.shape_type[s] == static_cast<int>(ShapeType::Plane);
  EXPECT_EQ(planes, 1);
  const State state = model.state();
  const int torso = second.body_map[1];
  EXPECT_NEAR(state.body_q[7 * torso], 2.0, 1e-12);
  EXPECT_NEAR(state.body_q[7 * torso + 2], 0.45, 1e-12);
  EXPECT_EQ(second.q_begin, 19);
}

TEST(MjcfImport, MissingFileIsAClearError) {
  ModelBuilder builder;
  try {
    builder.add_mjcf("/nonexistent/robot.xml");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'/nonexistent/robot.xml': file does not exist"), std::string::npos)
        << e.what();
  }
}

TEST(MjcfImport, ParseErrorPassesMujocosMessageOn) {
  const std::string path = test::write_temp_file("broken.xml", "<mujoco><worldbody><body></worldbody></mujoco>");
  ModelBuilder builder;
  try {
    builder.add_mjcf(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cannot load '" + path + "'"), std::string::npos) << what;
    EXPECT_NE(what.find("XML parse error"), std::string::npos) << what;
  }
  std::filesystem::remove(path);
}

TEST(MjcfImport, UrdfGoesThroughTheSameParser) {
  const std::string path = test::write_temp_file("arm.urdf", R"(
<robot name="arm">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0 0 0.25"/><mass value="1"/><inertia ixx="0.02" iyy="0.02" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.1" rpy="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
</robot>)");
  ModelBuilder builder;
  builder.add_urdf(path);
  const Model model = builder.finalize();
  EXPECT_EQ(model.joint_dof_count, 1);
  EXPECT_EQ(model.joint_limit_lower[0], -1);
  EXPECT_EQ(model.joint_limit_upper[0], 1);
  expect_matches_mujoco(path, 11);
  std::filesystem::remove(path);
}

TEST(MjcfImport, AUrdfsNanOrBrokenXmlIsNamedLikeAnMjcfs) {
  const std::string nan = test::write_temp_file("nan.urdf", R"(<robot name="r">
  <link name="base"><inertial><origin xyz="0 nan 0"/><mass value="1"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>)");
  const std::string broken = test::write_temp_file("broken.urdf", "<robot><link></robot>");
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(builder.add_urdf(nan),
                       R"(nan.urdf line 2: <origin> xyz="0 nan 0": 'nan' is not a number (NaN))");
  EXPECT_NOVAPHY_ERROR(builder.add_urdf(broken),
                       "broken.urdf': XML parse error at line 1: a closing tag that does not");
  std::filesystem::remove(nan);
  std::filesystem::remove(broken);
}

// a compiled model whose indices and types are corrupted: each is named by its field, element and value before
// the converter reads it (the same check guards the Python route, tests/python/test_mujoco_fuzz.py)
TEST(MjcfImport, ACorruptCompiledModelIsNamedByItsField) {
  const std::string path = test::write_temp_file("corrupt.xml", R"(<mujoco><compiler autolimits="true"/><worldbody>
  <body name="base"><freejoint/><geom name="torso" size="0.1"/>
    <body name="arm" pos="0.2 0 0"><joint name="elbow" range="-1 1"/><geom name="arm" size="0.05"/></body>
  </body></worldbody>
  <tendon><fixed name="t"><joint joint="elbow" coef="1"/></fixed></tendon>
  <equality><joint name="lock" joint1="elbow"/></equality>
  <actuator><motor name="drive" joint="elbow"/></actuator>
  <keyframe><key name="home"/></keyframe></mujoco>)");
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(path), mj_deleteModel);
  const auto corrupt = [&](auto* field, auto value, const std::string& message) {
    const auto kept = *field;
    *field = value;
    ModelBuilder builder;
    EXPECT_NOVAPHY_ERROR(import_mujoco_model(builder, m.get()), message);
    *field = kept;
  };
  corrupt(&m->jnt_qposadr[1], 99, "MjModel jnt_qposadr[1] (joint 'elbow'): 99 out of range [0, 8)");
  corrupt(&m->jnt_qposadr[1], 6, "MjModel jnt_qposadr[1] (joint 'elbow'): 6, expected 7");
  corrupt(&m->jnt_dofadr[1], -1, "MjModel jnt_dofadr[1] (joint 'elbow'): -1 out of range [0, 7)");
  corrupt(&m->jnt_type[1], 7, "MjModel jnt_type[1] (joint 'elbow'): 7 out of range [0, 4)");
  corrupt(&m->body_parentid[2], 2, "MjModel body_parentid[2] (body 'arm'): 2 out of range [0, 2)");
  corrupt(&m->body_jntnum[2], 5, "MjModel body_jntnum[2] (body 'arm'): 5 out of range [0, 2)");
  corrupt(&m->geom_bodyid[1], 3, "MjModel geom_bodyid[1] (geom 'arm'): 3 out of range [0, 3)");
  corrupt(&m->geom_type[0], -1, "MjModel geom_type[0] (geom 'torso'): -1 out of range [0, 9)");
  corrupt(&m->actuator_trnid[0], 2, "MjModel actuator_trnid[0][0] (actuator 'drive'): 2 out of range [0, 2)");
  corrupt(&m->actuator_gaintype[0], 1000, "MjModel actuator_gaintype[0] (actuator 'drive'): 1000 out of range [0, 7)");
  corrupt(&m->wrap_objid[0], 5, "MjModel wrap_objid[0] (tendon 't'): 5 out of range [0, 2)");
  corrupt(&m->tendon_num[0], 2, "MjModel tendon_num[0] (tendon 't'): 2 out of range [0, 2)");
  corrupt(&m->eq_obj1id[0], -1, "MjModel eq_obj1id[0] (equality 'lock'): -1 out of range [0, 2)");
  corrupt(&m->name_jntadr[1], m->nnames,
          "MjModel name_jntadr[1] (joint 1): " + std::to_string(m->nnames) + " out of range [0, " +
              std::to_string(m->nnames) + ")");
  corrupt(&m->key_qpos[7], std::nan(""), "MjModel key_qpos[0][7] (keyframe 'home') is not finite: nan");
  corrupt(&m->body_pos[6], -INFINITY, "MjModel body_pos[2][0] (body 'arm') is not finite: -inf");
  const std::array<mjtNum, 4> quat{};
  const std::array<mjtNum, 4> kept{m->body_quat[8], m->body_quat[9], m->body_quat[10], m->body_quat[11]};
  std::copy(quat.begin(), quat.end(), m->body_quat + 8);
  ModelBuilder builder;
  EXPECT_NOVAPHY_ERROR(import_mujoco_model(builder, m.get()), "MjModel body_quat[2] (body 'arm') is a zero quaternion");
  std::copy(kept.begin(), kept.end(), m->body_quat + 8);
  m->names[m->nnames - 1] = 'x';  // the last name, the keyframe's, without its NUL
  EXPECT_NOVAPHY_ERROR(import_mujoco_model(builder, m.get()),
                       "MjModel name_keyadr[0] (keyframe 0): the name at " + std::to_string(m->name_keyadr[0]) +
                           " has no NUL before the end of names (" + std::to_string(m->nnames) + " bytes)");
  std::filesystem::remove(path);
}

// seeded corruptions of the fields the converter reads, one to three at a time: each import raises Error or
// converts (under the sanitizer build, tools/test.sh, an out-of-bounds read fails it)
TEST(MjcfImport, RandomlyCorruptedCompiledModelsRaiseAnErrorOrConvert) {
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(NOVAPHY_TEST_MODEL_DIR "/fuzz.xml"),
                                                       mj_deleteModel);
  const std::vector<std::pair<int*, int>> indices = {{m->body_parentid, m->nbody},
                                                     {m->body_jntnum, m->nbody},
                                                     {m->body_jntadr, m->nbody},
                                                     {m->jnt_type, m->njnt},
                                                     {m->jnt_qposadr, m->njnt},
                                                     {m->jnt_dofadr, m->njnt},
                                                     {m->geom_type, m->ngeom},
                                                     {m->geom_bodyid, m->ngeom},
                                                     {m->geom_dataid, m->ngeom},
                                                     {m->geom_condim, m->ngeom},
                                                     {m->mesh_vertadr, m->nmesh},
                                                     {m->mesh_vertnum, m->nmesh},
                                                     {m->exclude_signature, m->nexclude},
                                                     {m->tendon_adr, m->ntendon},
                                                     {m->tendon_num, m->ntendon},
                                                     {m->wrap_type, m->nwrap},
                                                     {m->wrap_objid, m->nwrap},
                                                     {m->actuator_trntype, m->nu},
                                                     {m->actuator_dyntype, m->nu},
                                                     {m->actuator_gaintype, m->nu},
                                                     {m->actuator_biastype, m->nu},
                                                     {m->actuator_trnid, 2 * m->nu},
                                                     {m->eq_type, m->neq},
                                                     {m->eq_obj1id, m->neq},
                                                     {m->eq_obj2id, m->neq},
                                                     {m->name_bodyadr, m->nbody},
                                                     {m->name_jntadr, m->njnt},
                                                     {m->name_geomadr, m->ngeom},
                                                     {m->name_meshadr, m->nmesh},
                                                     {m->name_tendonadr, m->ntendon},
                                                     {m->name_actuatoradr, m->nu},
                                                     {m->name_keyadr, m->nkey},
                                                     {m->name_eqadr, m->neq}};
  const std::vector<std::pair<mjtNum*, int>> values = {
      {m->body_pos, 3 * m->nbody}, {m->body_quat, 4 * m->nbody},    {m->body_iquat, 4 * m->nbody},
      {m->jnt_axis, 3 * m->njnt},  {m->geom_quat, 4 * m->ngeom},    {m->key_qpos, m->nkey * m->nq},
      {m->qpos0, m->nq},           {m->eq_data, mjNEQDATA * m->neq}};
  std::mt19937 rng(1);
  const auto pick = [&](int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); };
  int raised = 0;
  constexpr int kTrials = 2000;
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<std::pair<int*, int>> kept_index;
    std::vector<std::pair<mjtNum*, mjtNum>> kept_value;
    for (int k = pick(3); k >= 0; --k)
      if (pick(4) > 0) {
        const auto [field, size] = indices[pick(indices.size())];
        int* x = field + pick(size);
        kept_index.push_back({x, *x});
        const int choices[] = {-1, -2, size, size + 1, INT_MAX, INT_MIN, pick(100) - 50};
        *x = choices[pick(7)];
      } else {
        const auto [field, size] = values[pick(values.size())];
        mjtNum* x = field + pick(size);
        kept_value.push_back({x, *x});
        const mjtNum choices[] = {std::nan(""), INFINITY, -INFINITY, 0, 1e300};
        *x = choices[pick(5)];
      }
    try {
      ModelBuilder builder;
      import_mujoco_model(builder, m.get());
      builder.finalize();
    } catch (const Error&) {
      ++raised;
    }
    for (auto it = kept_index.rbegin(); it != kept_index.rend(); ++it) *it->first = it->second;
    for (auto it = kept_value.rbegin(); it != kept_value.rend(); ++it) *it->first = it->second;
  }
  EXPECT_GT(raised, kTrials / 2);
}

}  // namespace
}  // namespace novaphy
