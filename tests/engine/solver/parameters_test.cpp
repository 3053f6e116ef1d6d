// Per-world parameters written at run time (Model::set_parameter) and the step: a solver made before the writes
// steps bit for bit as one made after them (what depends on the parameters read again: the blocks' lanes, the
// welded links' masses, the actuators' and contacts' numbers, dry friction where there was none); the worlds not
// written step as if nothing had been; each world falls under its own gravity
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "engine/import/mjcf_import.h"
#include "solver_test_support.h"

namespace novaphy {
namespace {

using solver_test::Scene;
using solver_test::world_state;

constexpr int kWorlds = 5;

ModelBuilder worlds_of(const ModelBuilder& robot, Precision precision) {
  ModelBuilder worlds;
  worlds.set_precision(precision);
  worlds.replicate(robot, kWorlds);
  return worlds;
}

ModelBuilder file_worlds(const std::string& file, Precision precision) {
  ModelBuilder robot;
  import_mjcf(robot, file);
  return worlds_of(robot, precision);
}

// a free base on the floor with an arm on a hinge and a tool welded to the arm (a Fixed joint: merged into the
// arm's link), the hinge driven by a position servo
ModelBuilder welded_worlds(Precision precision) {
  ModelBuilder robot;
  const int base = robot.add_body(RigidBody::from_box(2, Vec3(0.2, 0.1, 0.2)), Transform{Vec3(0, 0.12, 0)}, "base");
  robot.add_joint_free(-1, base);
  robot.add_shape_box(base, Vec3(0.2, 0.1, 0.2));
  const int arm = robot.add_body(RigidBody::from_box(0.5, Vec3(0.3, 0.03, 0.03)), Transform{Vec3(0.3, 0.3, 0)}, "arm");
  JointOptions hinge;
  hinge.dof.axis = Vec3(0, 0, 1);
  hinge.parent_xform = Transform{Vec3(0, 0.18, 0)};
  hinge.child_xform = Transform{Vec3(-0.3, 0, 0)};
  const int j = robot.add_joint_revolute(base, arm, hinge);
  const int tool = robot.add_body(RigidBody::from_sphere(0.2, 0.05), Transform{Vec3(0.6, 0.3, 0)}, "tool");
  JointOptions weld;
  weld.parent_xform = Transform{Vec3(0.3, 0, 0)};
  robot.add_joint_fixed(arm, tool, weld);
  robot.add_position(j, 20, 1);
  robot.add_ground_plane(0);
  return worlds_of(robot, precision);
}

// worlds `worlds` of the model given other parameters: every field of Model::parameter_names but the ranges and
// priorities, each entry moved by a random factor (centres of mass by an offset; armature, damping and dry friction
// also raised from 0), each body's inertia scaled by one factor
void randomise(Model& model, const std::vector<int>& worlds, std::mt19937& rng) {
  std::uniform_real_distribution<Scalar> factor(0.8, 1.2), offset(-0.01, 0.01);
  struct Field {
    const char* name;
    std::vector<Scalar> Model::*field;
    int width;
  };
  const Field fields[] = {{"body_mass", &Model::body_mass, 1},
                          {"body_com", &Model::body_com, 3},
                          {"body_inertia", &Model::body_inertia, 9},
                          {"joint_armature", &Model::joint_armature, 1},
                          {"joint_damping", &Model::joint_damping, 1},
                          {"joint_frictionloss", &Model::joint_frictionloss, 1},
                          {"joint_stiffness", &Model::joint_stiffness, 1},
                          {"shape_mu", &Model::shape_mu, 1},
                          {"actuator_gain", &Model::actuator_gain, 1},
                          {"actuator_bias", &Model::actuator_bias, 3},
                          {"world_gravity", &Model::world_gravity, 3}};
  for (const Field& f : fields) {
    const std::string name = f.name;
    std::vector<Scalar> values;
    for (const int w : worlds)
      for (const int i : model.parameter_entries(name, w)) {
        const Scalar scale = factor(rng);
        for (int m = 0; m < f.width; ++m) {
          const Scalar x = (model.*f.field)[static_cast<size_t>(i) * f.width + m];
          if (name == "body_com")
            values.push_back(x + offset(rng));
          else if (name == "body_inertia")
            values.push_back(x * scale);
          else if (name == "joint_armature" || name == "joint_damping" || name == "joint_frictionloss")
            values.push_back(x * factor(rng) + 0.02);
          else
            values.push_back(x * factor(rng));
        }
      }
    model.set_parameter(name, worlds, values);
  }
}

// random commands for every actuator
void command(Control& control, std::mt19937& rng) {
  std::uniform_real_distribution<Scalar> u(-1, 1);
  for (Scalar& c : control.actuator_ctrl) c = u(rng);
}

// a solver made before worlds {1, 3} are randomised steps as one made on the randomised model, bit for bit
void expect_read_as_made(const ModelBuilder& builder, int steps) {
  Scene live(builder);
  std::mt19937 rng(7);
  randomise(live.model, {1, 3}, rng);
  Model made = builder.finalize();
  made.copy_parameters(live.model);
  CollisionPipeline pipeline(made);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstone solver(made);
  State state = made.state();
  Control control = made.control();
  std::mt19937 commands(11);
  for (int k = 0; k < steps; ++k) {
    command(live.control, commands);
    control.actuator_ctrl = live.control.actuator_ctrl;
    live.run(0.002, 0.002);
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.002);
  }
  EXPECT_EQ(live.state.joint_q, state.joint_q);
  EXPECT_EQ(live.state.joint_qd, state.joint_qd);
  EXPECT_EQ(live.state.body_q, state.body_q);
}

TEST(Parameters, ReadAtTheNextStepAsASolverMadeWithThem) {
  for (const Precision precision : {Precision::Float64, Precision::Float32}) {
    SCOPED_TRACE(precision_name(precision));
    expect_read_as_made(file_worlds(NOVAPHY_SCENE_DIR "/quadruped.xml", precision), 150);
    expect_read_as_made(file_worlds(NOVAPHY_TEST_MODEL_DIR "/arm.xml", precision), 150);
    expect_read_as_made(file_worlds(NOVAPHY_TEST_MODEL_DIR "/hand.xml", precision), 150);
    expect_read_as_made(welded_worlds(precision), 150);
  }
}

TEST(Parameters, WorldsNotWrittenStepAsIfNothingWere) {
  const ModelBuilder builder = file_worlds(NOVAPHY_SCENE_DIR "/quadruped.xml", Precision::Float32);
  Scene written(builder), untouched(builder);
  written.run(0.1, 0.002);
  untouched.run(0.1, 0.002);
  std::mt19937 rng(3);
  randomise(written.model, {1, 3}, rng);
  written.run(0.2, 0.002);
  untouched.run(0.2, 0.002);
  for (int w = 0; w < kWorlds; ++w) {
    const bool changed = w == 1 || w == 3;
    EXPECT_EQ(world_state(written.model, written.state, w) == world_state(untouched.model, untouched.state, w),
              !changed)
        << "world " << w;
  }
}

TEST(Parameters, EachWorldFallsUnderItsOwnGravity) {
  ModelBuilder robot;
  const int box = robot.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)), Transform{Vec3(0, 5, 0)});
  robot.add_joint_free(-1, box);
  ModelBuilder worlds;
  worlds.replicate(robot, 3);
  Scene scene(worlds);
  scene.model.set_parameter("world_gravity", {1, 2}, {0, 0, 0, 4, 0, 0});
  const int steps = 100;
  const Scalar dt = 0.002, t = steps * dt;
  scene.run(t, dt);
  // semi-implicit Euler: after n steps the velocity is n g dt and the position moved by g dt^2 n (n + 1) / 2
  const Scalar moved = dt * dt * steps * (steps + 1) / 2;
  EXPECT_NEAR(scene.position(0).y(), 5 - 9.81 * moved, 1e-9);
  EXPECT_EQ(scene.position(1), Vec3(0, 5, 0));
  EXPECT_NEAR(scene.position(2).x(), 4 * moved, 1e-9);
  EXPECT_EQ(scene.position(2).y(), 5);
}

}  // namespace
}  // namespace novaphy
