// Model::set_parameter: which entries each world's values go to, and bad values refused by name before anything is
// written
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "engine/model/builder.h"
#include "engine/model/error.h"

namespace novaphy {
namespace {

// three worlds of a two-link arm on a motor, each with a box shape, and a static floor
Model three_worlds() {
  ModelBuilder robot;
  const int base = robot.add_body(RigidBody::from_box(2, Vec3(0.1, 0.1, 0.1)), Transform{Vec3(0, 1, 0)}, "base");
  robot.add_joint_free(-1, base);
  const int arm = robot.add_body(RigidBody::from_box(1, Vec3(0.3, 0.05, 0.05)), Transform{Vec3(0.3, 1, 0)}, "arm");
  JointOptions hinge;
  hinge.name = "hinge";
  hinge.dof.axis = Vec3(0, 0, 1);
  const int j = robot.add_joint_revolute(base, arm, hinge);
  ActuatorOptions motor;
  motor.name = "motor";
  motor.gain = 3;
  motor.ctrl_lower = -1, motor.ctrl_upper = 1;
  robot.add_actuator(j, motor);
  robot.add_shape_box(base, Vec3(0.1, 0.1, 0.1));
  ModelBuilder worlds;
  worlds.add_ground_plane(0);
  worlds.replicate(robot, 3);
  return worlds.finalize();
}

std::vector<int> entries(const Model& model, const std::string& field, int w) {
  const std::span<const int> e = model.parameter_entries(field, w);
  return {e.begin(), e.end()};
}

std::string error_of(Model& model, const std::string& field, const std::vector<int>& worlds,
                     const std::vector<Scalar>& values) {
  try {
    model.set_parameter(field, worlds, values);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Parameters, EachWorldsValuesGoToItsOwnEntries) {
  Model model = three_worlds();
  EXPECT_EQ(entries(model, "body_mass", 1), (std::vector<int>{2, 3}));
  EXPECT_EQ(model.parameter_entries("joint_damping", 2).size(), 7u);  // a Free joint's 6 dofs and the hinge's
  EXPECT_EQ(model.parameter_entries("shape_mu", 0).size(), 1u);       // the floor belongs to no world
  EXPECT_EQ(entries(model, "world_gravity", 2), (std::vector<int>{2}));
  const std::vector<Scalar> before = model.body_mass;
  model.set_parameter("body_mass", {2, 0}, {5, 6, 7, 8});
  EXPECT_EQ(model.body_mass[4], 5);
  EXPECT_EQ(model.body_mass[5], 6);
  EXPECT_EQ(model.body_mass[0], 7);
  EXPECT_EQ(model.body_mass[1], 8);
  EXPECT_EQ(model.body_mass[2], before[2]);
  model.set_parameter("world_gravity", {1}, {0, 0, -1});
  EXPECT_EQ(model.world_gravity[5], -1);
  EXPECT_EQ(model.world_gravity[1], -9.81);
  model.set_parameter("shape_priority", {0, 1, 2}, {1, 2, 3});
  EXPECT_EQ(model.shape_priority[model.parameter_entries("shape_priority", 2)[0]], 3);
}

TEST(Parameters, MarkTheWorldsWritten) {
  Model model = three_worlds();
  EXPECT_EQ(model.parameter_writes, 0u);
  model.set_parameter("joint_armature", {1}, std::vector<Scalar>(7, 0.1));
  model.set_parameter("actuator_gain", {2}, {4});
  EXPECT_EQ(model.parameter_writes, 2u);
  EXPECT_EQ(model.world_parameter_write, (std::vector<std::uint64_t>{0, 1, 2}));
}

TEST(Parameters, BadValuesAreRefusedByNameAndNothingIsWritten) {
  Model model = three_worlds();
  const Model before = model;
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  const Scalar inf = std::numeric_limits<Scalar>::infinity();
  auto refused = [&](const std::string& field, const std::vector<int>& worlds, const std::vector<Scalar>& values,
                     const std::string& says) {
    const std::string e = error_of(model, field, worlds, values);
    EXPECT_NE(e.find(says), std::string::npos) << field << ": " << e;
  };
  refused("joint_type", {0}, {1}, "'joint_type' is not a per-world parameter");
  refused("body_mass", {3}, {1, 1}, "world id 3 out of range [0, 3)");
  refused("body_mass", {0, 1}, {1, 1, 1}, "3 values for 2 worlds, expected 4");
  // the first world's values are good: the second's bad one stops the call before either is written
  refused("body_mass", {0, 1}, {1, 1, 1, nan}, "world 1, body 3 ('arm'): mass is not finite");
  refused("body_mass", {2}, {-1, 1}, "world 2, body 4 ('base'): mass must be > 0");
  std::vector<Scalar> flat(18, 0);
  for (int k : {0, 4, 8, 9, 13}) flat[k] = 1;
  flat[17] = 3;  // the arm's principal moments 1, 1, 3
  refused("body_inertia", {0}, flat, "body 1 ('arm'): inertia violates the triangle inequality");
  std::vector<Scalar> two(18, 0);
  for (int k : {0, 4, 8, 9, 13, 17}) two[k] = 1;
  two[13] = -1;
  refused("body_inertia", {0}, two, "body 1 ('arm'): inertia is not positive definite");
  refused("actuator_gain", {1}, {-2}, "world 1, actuator 1 ('motor'): the value must be finite and >= 0, got -2");
  refused("joint_damping", {0}, {0, 0, 0, 0, 0, 0, -0.1}, "dof 6 of joint 1 ('hinge')");
  refused("actuator_ctrl_lower", {0}, {2}, "the range must satisfy lower <= upper, got [2, 1]");
  refused("actuator_force_upper", {0}, {nan}, "the range must satisfy lower <= upper");
  refused("world_gravity", {0}, {0, inf, 0}, "world 0, world 0: the value is not finite");
  refused("shape_priority", {0}, {0.5}, "must be a whole number");
  refused("shape_mu", {0}, {-1}, "shape 1");
  EXPECT_EQ(model.body_mass, before.body_mass);
  EXPECT_EQ(model.body_inertia, before.body_inertia);
  EXPECT_EQ(model.parameter_writes, 0u);
  // an unlimited range end is a range
  model.set_parameter("actuator_ctrl_lower", {0}, {-inf});
  EXPECT_EQ(model.actuator_ctrl_lower[0], -inf);
}

}  // namespace
}  // namespace novaphy
