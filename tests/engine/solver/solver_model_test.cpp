#include "engine/solver/solver_model.h"

#include <gtest/gtest.h>

#include <vector>

#include "engine/model/builder.h"

namespace novaphy {
namespace {

// a robot of two Revolute links, the first limited, with a body welded onto the second by a Fixed joint, a motor on
// each joint and a tendon over both (limited when `tendon_limit`), beside a loose box: three such worlds
Model robots(bool tendon_limit) {
  ModelBuilder robot;
  const int link0 = robot.add_body(RigidBody::from_box(1, Vec3(0.05, 0.2, 0.05)));
  const int link1 = robot.add_body(RigidBody::from_box(1, Vec3(0.05, 0.2, 0.05)));
  const int tip = robot.add_body(RigidBody::from_sphere(0.5, 0.05));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.dof.limit_lower = -1;
  options.dof.limit_upper = 1;
  const int joint0 = robot.add_joint_revolute(-1, link0, options);
  options.dof.limit_lower = -kUnbounded;
  options.dof.limit_upper = kUnbounded;
  options.parent_xform.p = Vec3(0, -0.4, 0);
  const int joint1 = robot.add_joint_revolute(link0, link1, options);
  JointOptions weld;
  weld.parent_xform.p = Vec3(0, -0.25, 0);
  robot.add_joint_fixed(link1, tip, weld);
  robot.add_motor(joint0, 2);
  robot.add_motor(joint1, 2);
  TendonOptions tendon;
  if (tendon_limit) tendon.limit_upper = 0.5;
  robot.add_tendon({joint0, joint1}, {1, 1}, tendon);
  robot.add_body(RigidBody::from_box(3, Vec3::Constant(0.1)), Transform{Vec3(1, 1, 0)});
  ModelBuilder worlds;
  worlds.replicate(robot, 3);
  return worlds.finalize();
}

// each world's robot is an articulation of two links with the tip welded into the second, its box another of six
// dofs; every body and dof sits in its world's articulations
TEST(SolverModel, IndexesEachBodyAndDofByItsArticulation) {
  const Model model = robots(false);
  const SolverModel built(model, true);
  ASSERT_EQ(model.articulation_count, 6);
  ASSERT_EQ(built.art.size(), 6u);
  int welded = 0;
  for (int a = 0; a < model.articulation_count; ++a) {
    const bool robot = built.art[a].dof_count() == 2;
    EXPECT_EQ(built.art[a].dof_count(), robot ? 2 : 6);
    EXPECT_EQ(built.index.dof_count[a], built.art[a].dof_count());
    EXPECT_EQ(built.welded_into[a].size(), robot ? 1u : 0u);
    for (const WeldedBody& w : built.welded_into[a]) {
      ++welded;
      EXPECT_EQ(w.link, 1);
      EXPECT_EQ(built.index.body_articulation[w.body], a);
      EXPECT_EQ(built.index.body_link[w.body], 1);
    }
    for (int k = built.art[a].qd_begin(); k < built.art[a].qd_begin() + built.art[a].dof_count(); ++k)
      EXPECT_EQ(built.index.dof_articulation[k], a);
  }
  EXPECT_EQ(welded, 3);
  for (int b = 0; b < model.body_count; ++b) {
    const int a = built.index.body_articulation[b];
    ASSERT_GE(a, 0);
    EXPECT_EQ(model.body_world[model.joint_child[model.articulation_start[a]]], model.body_world[b]);
  }
  // without welding the tip is a link of its own
  const SolverModel unwelded(model, false);
  for (int a = 0; a < model.articulation_count; ++a) EXPECT_TRUE(unwelded.welded_into[a].empty());
}

// the first joint of each robot is its only limited one; each dof's motor in order, the three worlds' motors
// sharing one row of parameters; each articulation's bodies one run, each robot's actuators one run and its tendon
TEST(SolverModel, GroupsLimitsActuatorsAndInputsByArticulation) {
  const Model model = robots(false);
  const SolverModel built(model, true);
  ASSERT_EQ(built.limited_joints.size(), 3u);
  for (size_t m = 0; m < built.limited_joints.size(); ++m) {
    const int j = built.limited_joints[m];
    EXPECT_EQ(model.joint_limit_upper[model.joint_qd_start[j]], 1);
    EXPECT_EQ(built.limit_slot[model.joint_qd_start[j]], static_cast<int>(m));
  }
  for (int a = 0; a < model.articulation_count; ++a)
    EXPECT_EQ(built.limited_start[a + 1] - built.limited_start[a], built.art[a].dof_count() == 2 ? 1 : 0);
  EXPECT_EQ(built.actuator_params.size(), 1u);
  for (int d = 0; d < model.joint_dof_count; ++d) {
    const bool robot = built.index.dof_count[built.index.dof_articulation[d]] == 2;
    ASSERT_EQ(built.dof_actuator_start[d + 1] - built.dof_actuator_start[d], robot ? 1 : 0);
    if (!robot) continue;
    const SolverModel::DofActuator& u = built.dof_actuators[built.dof_actuator_start[d]];
    EXPECT_EQ(model.joint_qd_start[model.actuator_joint[u.u]], d);
    EXPECT_EQ(u.params, 0);
  }
  for (int a = 0; a < model.articulation_count; ++a) {
    const bool robot = built.art[a].dof_count() == 2;
    EXPECT_EQ(built.art_body_start[a + 1] - built.art_body_start[a], 1);
    EXPECT_EQ(built.art_body_runs[2 * built.art_body_start[a] + 1], robot ? 3 : 1);
    EXPECT_EQ(built.art_actuator_start[a + 1] - built.art_actuator_start[a], robot ? 1 : 0);
    EXPECT_EQ(built.art_tendon_start[a + 1] - built.art_tendon_start[a], robot ? 1 : 0);
  }
  EXPECT_TRUE(built.loose_bodies.empty());
  EXPECT_TRUE(built.loose_actuators.empty());
}

// a tendon limit makes its robot's rows the islands'; the box's linear dofs weigh its mass over its mass
TEST(SolverModel, MarksConstrainedArticulationsAndWeighsEnergy) {
  for (const bool limit : {false, true}) {
    const Model model = robots(limit);
    const SolverModel built(model, true);
    for (int a = 0; a < model.articulation_count; ++a) {
      const bool robot = built.art[a].dof_count() == 2;
      EXPECT_EQ(built.constrained[a], limit && robot ? 1 : 0);
      if (robot) continue;
      for (int k = 3; k < 6; ++k) EXPECT_NEAR(built.energy_weight[built.art[a].qd_begin() + k], 1, 1e-12);
    }
  }
}

}  // namespace
}  // namespace novaphy
