// A joint's dry friction (frictionloss): a box-constrained row per dof, the same on the blocks and the dense
// route, each world of a batch as it steps alone.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include "engine/eval/eval.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support.h"

namespace novaphy {
namespace {

// a link on a hinge about Z (no gravity) driven by a motor, its dry friction `loss`
Model turning_link(Scalar loss, int worlds = 1, Precision precision = Precision::Float64) {
  ModelBuilder robot(Vec3::Zero());
  const int link = robot.add_body(RigidBody::from_box(1, Vec3(0.2, 0.05, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.dof.frictionloss = loss;
  options.child_xform.p = Vec3(-0.2, 0, 0);
  robot.add_motor(robot.add_joint_revolute(-1, link, options));
  ModelBuilder batch(Vec3::Zero());
  batch.set_precision(precision);
  batch.replicate(robot, worlds);
  return batch.finalize();
}

State step(const Model& model, const Control& control, int steps, bool blocks) {
  SolverFeatherstoneSettings settings;
  settings.use_batch_kernels = blocks;
  settings.angular_damping = 0;
  return test::run_steps(model, control, steps, 0.01, settings);
}

TEST(FrictionLoss, HoldsAJointAgainstASmallerTorqueAndTakesItsShareOfALargerOne) {
  const Model model = turning_link(0.5);
  Control control = model.control();
  const Scalar inertia = eval_mass_matrix(model, model.state())(0, 0), dt = 0.01;
  for (const bool blocks : {true, false}) {
    control.actuator_ctrl[0] = 0.4;  // below the friction: the joint stays (but for the rows' cfm softness)
    EXPECT_LT(std::abs(step(model, control, 50, blocks).joint_q[0]), 1e-8) << (blocks ? "blocks" : "dense");
    control.actuator_ctrl[0] = 2;  // above it: one step from rest gains dt (2 - 0.5) / I
    EXPECT_NEAR(step(model, control, 1, blocks).joint_qd[0], dt * 1.5 / inertia, 1e-12)
        << (blocks ? "blocks" : "dense");
  }
}

TEST(FrictionLoss, EachWorldOfABatchStepsAsItDoesAlone) {
  // every world its own friction and torque: some stick, some slip
  constexpr int kWorlds = 21;
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    Model batch = turning_link(0, kWorlds, precision);
    Control control = batch.control();
    for (int w = 0; w < kWorlds; ++w) {
      batch.joint_frictionloss[w] = 0.1 * w;
      control.actuator_ctrl[w] = 1 + std::sin(w);
    }
    const State stepped = step(batch, control, 40, true);
    for (int w = 0; w < kWorlds; ++w) {
      Model alone = turning_link(0.1 * w, 1, precision);
      Control alone_control = alone.control();
      alone_control.actuator_ctrl[0] = 1 + std::sin(w);
      const State s = step(alone, alone_control, 40, true);
      ASSERT_EQ(std::memcmp(&stepped.joint_qd[w], s.joint_qd.data(), sizeof(Scalar)), 0) << "world " << w;
      ASSERT_EQ(std::memcmp(&stepped.joint_q[w], s.joint_q.data(), sizeof(Scalar)), 0) << "world " << w;
    }
  }
}

// a chain of three links on hinges about Z (no gravity), each driven by a motor, with the dry friction `loss[k]`
Model turning_chain(const std::vector<std::array<Scalar, 3>>& loss, Precision precision) {
  ModelBuilder batch(Vec3::Zero());
  batch.set_precision(precision);
  for (const auto& world_loss : loss) {
    ModelBuilder robot(Vec3::Zero());
    int parent = -1;
    for (int k = 0; k < 3; ++k) {
      const int link = robot.add_body(RigidBody::from_box(1, Vec3(0.2, 0.05, 0.05)));
      JointOptions options;
      options.dof.axis = Vec3::UnitZ();
      options.dof.frictionloss = world_loss[k];
      options.child_xform.p = Vec3(-0.2, 0, 0);
      options.parent_xform.p = Vec3(parent < 0 ? 0 : 0.2, 0, 0);
      robot.add_motor(robot.add_joint_revolute(parent, link, options));
      parent = link;
    }
    batch.add_builder(robot);
  }
  return batch.finalize();
}

TEST(FrictionLoss, EachDofOfEachWorldKeepsItsOwnImpulse) {
  // the kept impulses start the next step's rows (warm start): a world's dofs, of their own friction and torques
  // (some stick, some slip, changing over the steps), step as the same world's do alone, on the blocks and on the
  // dense route (whose rows are the islands', which also take a block's articulation while a contact joins it to
  // another)
  constexpr int kWorlds = 19, kSteps = 30;
  std::vector<std::array<Scalar, 3>> loss(kWorlds);
  for (int w = 0; w < kWorlds; ++w)
    for (int k = 0; k < 3; ++k) loss[w][k] = 0.05 * ((w + 2 * k) % 7);
  auto torque = [](int w, int k) { return 0.6 * std::sin(1.3 * w + 2.1 * k); };
  for (const Precision precision : {Precision::Float32, Precision::Float64})
    for (const bool blocks : {true, false}) {
      const Model batch = turning_chain(loss, precision);
      Control control = batch.control();
      for (int w = 0; w < kWorlds; ++w)
        for (int k = 0; k < 3; ++k) control.actuator_ctrl[3 * w + k] = torque(w, k);
      const State stepped = step(batch, control, kSteps, blocks);
      for (int w = 0; w < kWorlds; ++w) {
        const Model alone = turning_chain({loss[w]}, precision);
        Control alone_control = alone.control();
        for (int k = 0; k < 3; ++k) alone_control.actuator_ctrl[k] = torque(w, k);
        const State s = step(alone, alone_control, kSteps, blocks);
        ASSERT_EQ(std::memcmp(&stepped.joint_qd[3 * w], s.joint_qd.data(), 3 * sizeof(Scalar)), 0)
            << "world " << w << (blocks ? ", blocks" : ", dense");
        ASSERT_EQ(std::memcmp(&stepped.joint_q[3 * w], s.joint_q.data(), 3 * sizeof(Scalar)), 0)
            << "world " << w << (blocks ? ", blocks" : ", dense");
      }
    }
}

}  // namespace
}  // namespace novaphy
