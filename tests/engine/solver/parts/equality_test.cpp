// Equality constraints (model.h: connect, joint coupling) and tendon limits, held by rows of the step: a
// four-bar loop closed by a connect (on a fixed base beside MuJoCo, on a free-floating base as in cassie's
// legs), fingers coupled as panda's, a tendon kept in its range, on both routes; each world of a batch as it
// steps alone; bad input named.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "engine/collision/pipeline.h"
#include "engine/import/mjcf_import.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support.h"
#include "test_support_errors.h"
#include "tools/mujoco_oracle.h"

namespace novaphy {
namespace {

// a four-bar in the x-z plane: a crank driven by a motor, a coupler and a rocker, the coupler's tip connected
// to the rocker's; `base` is the joint of the body carrying both pivots
std::string four_bar(const std::string& base) {
  return R"(
<mujoco model="four bar">
  <option gravity="0 0 -9.81" timestep="0.002"/>
  <worldbody>
    <body name="base" pos="0 0 1">)" +
         base + R"(
      <geom type="box" size="0.25 0.05 0.02" pos="0.2 0 0.05" mass="2"/>
      <body name="crank">
        <joint name="crank" type="hinge" axis="0 1 0" damping="0.05"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.3"/>
        <body name="coupler" pos="0 0 -0.2">
          <joint name="coupler" type="hinge" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0.4 0 -0.1" size="0.02" mass="0.4"/>
        </body>
      </body>
      <body name="rocker" pos="0.4 0 0">
        <joint name="rocker" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.3"/>
      </body>
    </body>
  </worldbody>
  <equality><connect name="closure" body1="coupler" body2="rocker" anchor="0.4 0 -0.1" solref="0.004 1" solimp="0.99 0.999 0.001"/></equality>
  <actuator><motor name="drive" joint="crank" ctrllimited="true" ctrlrange="-1 1"/></actuator>
</mujoco>)";
}

// the gap between the connect's two anchors at the state's body poses
Scalar connect_gap(const Model& model, const State& state, int e) {
  auto anchor = [&](int k) {
    const int b = model.equality_object[2 * e + k];
    const Vec3 a(&model.equality_data[10 * e + 3 * k]);
    return b < 0 ? a : Transform::from_array(&state.body_q[7 * b]).apply(a);
  };
  return (anchor(1) - anchor(0)).norm();
}

// MuJoCo 2.2.2's qpos[0] after `steps` steps of the file from qpos0 with its first actuator's ctrl held
Scalar mujoco_first_coordinate(const std::string& path, Scalar ctrl, int steps) {
  mjModel* m = load_mujoco_model(path);
  mjData* d = mj_makeData(m);
  d->ctrl[0] = ctrl;
  for (int k = 0; k < steps; ++k) mj_step(m, d);
  const Scalar q = d->qpos[0];
  mj_deleteData(d);
  mj_deleteModel(m);
  return q;
}

SolverFeatherstoneSettings route(bool blocks) {
  SolverFeatherstoneSettings settings;
  settings.use_batch_kernels = blocks;
  return settings;
}

TEST(Equalities, AFourBarStaysClosedAndMovesAsMujocosOnAFixedBase) {
  const std::string path = test::write_temp_file("four_bar.xml", four_bar(""));
  ModelBuilder builder;
  ASSERT_TRUE(builder.add_mjcf(path).empty());
  const Model model = builder.finalize();
  ASSERT_EQ(model.equality_count, 1);
  EXPECT_LT(connect_gap(model, model.state(), 0), 1e-12);  // the compiled anchors coincide at qpos0
  Control control = model.control();
  control.actuator_ctrl[0] = 0.6;
  const Scalar mujoco = mujoco_first_coordinate(path, 0.6, 500);  // MuJoCo 2.2.2 on the same file, 1 s
  for (const bool blocks : {true, false}) {
    SolverFeatherstoneSettings settings = route(blocks);
    settings.angular_damping = 0;
    const State s = test::run_steps(model, control, 500, 0.002, settings);
    EXPECT_LT(connect_gap(model, s, 0), 1e-3) << (blocks ? "blocks" : "dense");
    // the loop's one dof: the crank turned as MuJoCo's, its connect made nearly hard (solref, solimp; at
    // MuJoCo's default softness the loop gives and the crank turns 0.42 rad against 0.36)
    EXPECT_GT(std::abs(mujoco), 0.3);
    EXPECT_NEAR(s.joint_q[0], mujoco, 0.005) << (blocks ? "blocks" : "dense");
  }
  std::filesystem::remove(path);
}

TEST(Equalities, TheFourBarsDynamicsMatchMujocosWithConstraintsOff) {
  const std::string path = test::write_temp_file("four_bar_oracle.xml", four_bar(R"(<freejoint/>)"));
  MujocoOracle oracle(path);
  ASSERT_EQ(oracle.model().equality_count, 1);
  std::mt19937 rng(11);
  OracleErrors worst;
  for (int k = 0; k < 20; ++k) worst.accumulate(oracle.compare_random_state(rng));
  EXPECT_LT(worst.max(), 1e-9);
  std::filesystem::remove(path);
}

TEST(Equalities, ACassieLikeLoopOnAFreeBaseStaysClosed) {
  const std::string path = test::write_temp_file("four_bar_free.xml", four_bar(R"(<freejoint/>)"));
  ModelBuilder builder;
  ASSERT_TRUE(builder.add_mjcf(path).empty());
  const Model model = builder.finalize();
  Control control = model.control();
  control.actuator_ctrl[0] = 1;
  for (const bool blocks : {true, false}) {
    const State s = test::run_steps(model, control, 1000, 0.002, route(blocks));
    EXPECT_LT(connect_gap(model, s, 0), 1e-3) << (blocks ? "blocks" : "dense");
    EXPECT_LT(s.joint_q[2], -5);  // the base fell freely for 2 s (z from 1 m)
  }
  std::filesystem::remove(path);
}

// a pendulum driven by a motor, a free box welded to its end and a second box welded to the world in the air at its
// centre (MuJoCo's welds made nearly hard: at its default solref, a weld to the world sags and swings, as NovaPhy's,
// tests/python/test_soft_constraints.py)
constexpr const char* kWeldedPendulum = R"(
<mujoco model="welded pendulum">
  <option gravity="0 0 -9.81" timestep="0.002"/>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="swing" type="hinge" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.5"/>
    </body>
    <body name="box" pos="0.42 0 0.98" euler="0 20 10"><freejoint/>
      <geom type="box" size="0.05 0.03 0.02" mass="0.4"/></body>
    <body name="hung" pos="1 0 2"><freejoint/><geom type="box" size="0.05 0.05 0.05" mass="1"/></body>
  </worldbody>
  <equality>
    <weld name="grip" body1="arm" body2="box" anchor="0.02 0 0" solref="0.004 1" solimp="0.99 0.999 0.001"/>
    <weld name="hook" body1="hung" anchor="1 0 2" solref="0.004 1" solimp="0.99 0.999 0.001"/>
  </equality>
  <actuator><motor name="drive" joint="swing"/></actuator>
</mujoco>)";

TEST(Equalities, AWeldHoldsABoxToAPendulumAsMujocosAndAnotherInTheAir) {
  const std::string path = test::write_temp_file("welded_pendulum.xml", kWeldedPendulum);
  ModelBuilder builder;
  ASSERT_TRUE(builder.add_mjcf(path).empty());
  const Model model = builder.finalize();
  ASSERT_EQ(model.equality_count, 2);
  Control control = model.control();
  control.actuator_ctrl[0] = 0.8;
  const Scalar mujoco = mujoco_first_coordinate(path, 0.8, 500);
  const State start = model.state();
  auto relative = [&](const State& s, int a, int b) {
    return Transform::from_array(&s.body_q[7 * a]).inverse() * Transform::from_array(&s.body_q[7 * b]);
  };
  const int arm = 0, box = 1, hung = 2;
  for (const bool blocks : {true, false}) {
    SolverFeatherstoneSettings settings = route(blocks);
    settings.angular_damping = 0;
    const State s = test::run_steps(model, control, 500, 0.002, settings);
    const Transform held = relative(start, arm, box), now = relative(s, arm, box);
    EXPECT_LT((now.p - held.p).norm(), 1e-3) << (blocks ? "blocks" : "dense");
    EXPECT_LT(held.q.angularDistance(now.q), 1e-3);
    EXPECT_GT(std::abs(mujoco), 0.3);
    EXPECT_NEAR(s.joint_q[0], mujoco, 0.005);  // the swing as MuJoCo's, box and all
    const Transform hung0 = Transform::from_array(&start.body_q[7 * hung]);
    const Transform hung1 = Transform::from_array(&s.body_q[7 * hung]);
    EXPECT_LT((hung1.p - hung0.p).norm(), 1e-3);  // it did not fall
    EXPECT_LT(hung0.q.angularDistance(hung1.q), 1e-3);
  }
  std::filesystem::remove(path);
}

TEST(Equalities, ABatchOfLoopsStepsAlikeOnOneThreadAndOnAll) {
  const std::string path = test::write_temp_file("four_bar_batch.xml", four_bar(R"(<freejoint/>)"));
  ModelBuilder robot, batch;
  robot.add_mjcf(path);
  batch.replicate(robot, 9, Vec3(1, 0, 0));
  const Model model = batch.finalize();
  Control control = model.control();
  for (int w = 0; w < 9; ++w) control.actuator_ctrl[w] = 0.1 * w - 0.4;
  State runs[2];
  for (const int threads : {1, 2}) {
    SolverFeatherstoneSettings settings;
    settings.num_threads = threads;
    runs[threads - 1] = test::run_steps(model, control, 300, 0.002, settings);
  }
  EXPECT_EQ(std::memcmp(runs[0].joint_q.data(), runs[1].joint_q.data(), runs[0].joint_q.size() * sizeof(Scalar)), 0);
  EXPECT_NE(runs[0].joint_q[7], runs[0].joint_q[7 + 10]);  // the worlds differ (crank angles)
  std::filesystem::remove(path);
}

// two fingers on slides, the second coupled to the first (panda's finger_joint2 = finger_joint1) and a
// third following the first's square; a servo drives the first only
Model coupled_fingers(int worlds) {
  ModelBuilder hand(Vec3(0, 0, -9.81));
  JointOptions slide;
  slide.dof.axis = Vec3::UnitY();
  int joints[3];
  for (int k = 0; k < 3; ++k) {
    const int finger = hand.add_body(RigidBody::from_box(0.05 + 0.02 * k, Vec3(0.01, 0.01, 0.03)));
    slide.parent_xform.p = Vec3(0.05 * k, 0, 0);
    joints[k] = hand.add_joint_prismatic(-1, finger, slide);
  }
  hand.add_position(joints[0], 100, 5);
  hand.add_joint_coupling(joints[1], joints[0], {0, 1, 0, 0, 0}, "mirror");
  hand.add_joint_coupling(joints[2], joints[0], {0.01, 0, 3, 0, 0}, "square");
  ModelBuilder batch(Vec3(0, 0, -9.81));
  batch.replicate(hand, worlds);
  return batch.finalize();
}

TEST(Equalities, CoupledFingersFollowTheDrivenOne) {
  const Model model = coupled_fingers(1);
  Control control = model.control();
  control.actuator_ctrl[0] = 0.04;
  for (const bool blocks : {true, false}) {
    const State s = test::run_steps(model, control, 1000, 0.002, route(blocks));
    const Scalar q0 = s.joint_q[0];
    EXPECT_NEAR(q0, 0.04, 2e-3) << (blocks ? "blocks" : "dense");
    EXPECT_NEAR(s.joint_q[1], q0, 1e-5);
    EXPECT_NEAR(s.joint_q[2], 0.01 + 3 * q0 * q0, 1e-5);
  }
}

TEST(Equalities, EachWorldOfABatchStepsAsItDoesAlone) {
  constexpr int kWorlds = 7;
  const Model batch = coupled_fingers(kWorlds);
  Control control = batch.control();
  for (int w = 0; w < kWorlds; ++w) control.actuator_ctrl[w] = 0.01 * w;
  const State stepped = test::run_steps(batch, control, 200, 0.002);
  const Model alone = coupled_fingers(1);
  for (int w = 0; w < kWorlds; ++w) {
    Control c = alone.control();
    c.actuator_ctrl[0] = 0.01 * w;
    const State s = test::run_steps(alone, c, 200, 0.002);
    ASSERT_EQ(std::memcmp(&stepped.joint_q[3 * w], s.joint_q.data(), 3 * sizeof(Scalar)), 0) << "world " << w;
  }
}

TEST(Tendons, ALimitedTendonStaysInItsRange) {
  // a slide on a slide, both pushed outwards by motors; their tendon (the sum of both) may not exceed 0.05
  ModelBuilder builder(Vec3::Zero());
  JointOptions slide;
  slide.dof.axis = Vec3::UnitX();
  int joints[2], parent = -1;
  for (int k = 0; k < 2; ++k) {
    const int b = builder.add_body(RigidBody::from_box(0.1, Vec3(0.01, 0.01, 0.01)));
    joints[k] = builder.add_joint_prismatic(parent, b, slide);
    builder.add_motor(joints[k]);
    parent = b;
  }
  TendonOptions options;
  options.limit_upper = 0.05;
  builder.add_tendon({joints[0], joints[1]}, {1, 1}, options);
  const Model model = builder.finalize();
  Control control = model.control();
  control.actuator_ctrl = {1, 0.5};
  for (const bool blocks : {true, false}) {
    const State s = test::run_steps(model, control, 500, 0.002, route(blocks));
    EXPECT_NEAR(s.joint_q[0] + s.joint_q[1], 0.05, 2e-3) << (blocks ? "blocks" : "dense");
  }
}

TEST(Equalities, BadInputIsNamed) {
  ModelBuilder builder;
  const int body = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)));
  EXPECT_NOVAPHY_ERROR(builder.add_connect(body, 7, Vec3::Zero(), "loop"),
                       "equality 0 ('loop') (connect): body2 index 7 out of range [-1, 1)");
  EXPECT_NOVAPHY_ERROR(builder.add_joint_coupling(0, -1, {0, 0, 0, 0, 0}),
                       "equality 0 (joint coupling): joint index 0 out of range [0, 0)");
  EXPECT_NOVAPHY_ERROR(builder.add_tendon({}, {}), "tendon 0: a tendon needs at least one joint");
  EXPECT_NOVAPHY_ERROR(builder.add_tendon_actuator(2), "actuator 0: tendon index 2 out of range [0, 0)");
  // an equality on a body the file does not have: MuJoCo's parser names it
  const std::string path = test::write_temp_file("missing_body.xml", R"(
<mujoco><worldbody><body name="a"><joint type="hinge"/><geom size="0.1"/></body></worldbody>
  <equality><connect body1="a" body2="nowhere" anchor="0 0 0"/></equality></mujoco>)");
  EXPECT_NOVAPHY_ERROR(builder.add_mjcf(path), "unknown element 'nowhere' in equality constraint 0");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace novaphy

namespace novaphy {
namespace {

// a leg whose thigh and shin (its grandchild, past a knee link) overlap deeply at the knee, as cassie's parts
// do, their contype and conaffinity keeping them from colliding with each other but not with the floor
std::string overlapping_leg(const char* conaffinity) {
  const std::string filter = std::string(R"(contype="1" conaffinity=")") + conaffinity + R"(")";
  return R"(
<mujoco>
  <option gravity="0 0 -9.81" timestep="0.002"/>
  <worldbody>
    <geom type="plane" size="5 5 0.1" contype="1" conaffinity="1"/>
    <body name="thigh" pos="0 0 0.5"><freejoint/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.06" )" +
         filter + R"(/>
      <body name="knee" pos="0 0 -0.2">
        <joint name="knee" type="hinge" axis="0 1 0" range="-0.5 0.5" damping="1"/>
        <geom type="sphere" size="0.02" contype="0" conaffinity="0"/>
        <body name="shin">
          <joint name="ankle" type="hinge" axis="1 0 0" range="-0.3 0.3" damping="1"/>
          <geom type="capsule" fromto="0 0 0.05 0 0 -0.25" size="0.05" )" +
         filter + R"(/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)";
}

TEST(Equalities, AFilteredSelfContactStaysFilteredWhileTheLegFalls) {
  // with conaffinity 0 on both links MuJoCo's rule filters the knee's overlap; with 1 it would collide
  for (const char* conaffinity : {"0", "1"}) {
    const std::string path = test::write_temp_file("overlapping_leg.xml", overlapping_leg(conaffinity));
    ModelBuilder builder;
    ASSERT_TRUE(builder.add_mjcf(path).empty());
    const Model model = builder.finalize();
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    pipeline.collide(model.state(), contacts);
    int self = 0;
    for (int k = 0; k < contacts.contact_count; ++k)
      self += contacts.contact_body_a[k] >= 0 && contacts.contact_body_b[k] >= 0;
    if (std::string(conaffinity) == "1") {
      EXPECT_GT(self, 0);
      continue;
    }
    EXPECT_EQ(self, 0);
    // it falls onto the floor and comes to rest there, calm: the knee's overlap never pushes it apart
    const State s = test::run_steps(model, model.control(), 1000, 0.002);
    for (const Scalar x : s.joint_qd) EXPECT_LT(std::abs(x), 0.05);
    EXPECT_GT(s.joint_q[2], 0);
    EXPECT_LT(s.joint_q[2], 0.5);
    std::filesystem::remove(path);
  }
}

}  // namespace
}  // namespace novaphy
