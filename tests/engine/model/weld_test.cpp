#include "engine/model/weld.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <limits>

#include "engine/eval/eval.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support.h"

namespace novaphy {
namespace {

// an arm: a free base, a hinge, a Fixed bracket, a slide, a Fixed tool on the bracket's child and a
// Fixed chain of two sensors off the base; the tool and the base carry boxes that reach the ground
ModelBuilder arm_with_fixed_links() {
  ModelBuilder builder(Vec3(0, 0, -9.81));
  builder.add_plane(Vec3::UnitZ(), 0);
  ShapeOptions shape;
  shape.mu = 0.8;
  auto body = [&](Scalar mass, const Vec3& half, const Vec3& com, const Vec3& at = Vec3::Zero()) {
    RigidBody rb = RigidBody::from_box(mass, half);
    rb.com = com;
    return builder.add_body(rb, Transform{at});
  };
  const int base = body(2, Vec3(0.2, 0.1, 0.05), Vec3(0.01, 0, 0), Vec3(0, 0, 0.8));
  builder.add_shape_box(base, Vec3(0.2, 0.1, 0.05), shape);
  const int upper = body(0.5, Vec3(0.03, 0.03, 0.2), Vec3(0, 0.01, -0.1));
  const int bracket = body(0.2, Vec3(0.05, 0.02, 0.02), Vec3(0.02, 0, 0));
  const int slider = body(0.3, Vec3(0.02, 0.02, 0.1), Vec3::Zero());
  const int tool = body(0.4, Vec3(0.05, 0.05, 0.05), Vec3(0, 0, -0.02));
  builder.add_shape_box(tool, Vec3(0.05, 0.05, 0.05), shape);
  const int sensor = body(0.05, Vec3(0.01, 0.01, 0.01), Vec3::Zero());
  const int sensor2 = body(0.05, Vec3(0.01, 0.01, 0.01), Vec3(0.005, 0, 0));

  builder.add_joint_free(-1, base);
  JointOptions hinge;
  hinge.dof.axis = Vec3(0, 1, 0);
  hinge.dof.limit_lower = -0.8;
  hinge.dof.limit_upper = 0.8;
  hinge.dof.target_ke = 20;
  hinge.dof.target_kd = 1;
  hinge.parent_xform.p = Vec3(0.15, 0, -0.05);
  hinge.child_xform.p = Vec3(0, 0, 0.2);
  builder.add_joint_revolute(base, upper, hinge);
  JointOptions weld;
  weld.parent_xform.p = Vec3(0, 0, -0.2);
  weld.parent_xform.q = Quat(Eigen::AngleAxis<Scalar>(0.4, Vec3::UnitX()));
  weld.child_xform.p = Vec3(-0.03, 0, 0);
  builder.add_joint_fixed(upper, bracket, weld);
  JointOptions slide;
  slide.dof.axis = Vec3(0, 0, 1);
  slide.dof.damping = 0.3;
  slide.parent_xform.p = Vec3(0.05, 0, 0);
  builder.add_joint_prismatic(bracket, slider, slide);
  weld.parent_xform.p = Vec3(0, 0, -0.1);
  weld.child_xform.p = Vec3(0, 0, 0.05);
  builder.add_joint_fixed(slider, tool, weld);
  weld.parent_xform.p = Vec3(-0.2, 0, 0.05);
  builder.add_joint_fixed(base, sensor, weld);
  weld.parent_xform.p = Vec3(0.02, 0, 0);
  builder.add_joint_fixed(sensor, sensor2, weld);
  return builder;
}

TEST(WeldFixedJoints, SameMassMatrixAndBiasWithFewerLinks) {
  const Model model = arm_with_fixed_links().finalize();
  const WeldedModel welded = weld_fixed_joints(model);
  EXPECT_EQ(model.joint_count, 7);
  EXPECT_EQ(welded.model.joint_count, 3);  // free, hinge, slide
  EXPECT_EQ(welded.welded_bodies.size(), 4u);
  EXPECT_EQ(welded.link_body[6], 0);  // the second sensor rides on the base
  EXPECT_EQ(welded.link_body[4], 3);  // the tool on the slider
  Scalar total = 0, welded_total = 0;
  for (int b = 0; b < model.body_count; ++b) total += model.body_mass[b], welded_total += welded.model.body_mass[b];
  EXPECT_NEAR(welded_total, total, 1e-12);

  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    State state = model.state();
    test::randomize_state(model, state, rng, false);
    EXPECT_LT(test::relative_error(eval_mass_matrix(welded.model, state), eval_mass_matrix(model, state)), 1e-12);
    EXPECT_LT(test::relative_error(eval_bias_forces(welded.model, state), eval_bias_forces(model, state)), 1e-12);
  }
  const WeldedModel unwelded = weld_fixed_joints(model, false);
  EXPECT_TRUE(unwelded.welded_bodies.empty());
  EXPECT_EQ(unwelded.model.body_count, 0);  // no copy: the original is the model to use
  EXPECT_EQ(unwelded.link_body[4], 4);
}

// the solver with welded links steps as it does with the Fixed links in its kernels: contacts on a
// welded tool, a wrench applied to a welded sensor, limits, a drive, damping
TEST(WeldFixedJoints, SolverStepsTheSameWeldedOrNot) {
  const ModelBuilder builder = arm_with_fixed_links();
  const Model model = builder.finalize();
  auto run = [&](bool weld) {
    SolverFeatherstoneSettings settings;
    settings.weld_fixed_joints = weld;
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    SolverFeatherstone solver(model, settings);
    State state = model.state();
    Control control = model.control();
    control.joint_target_pos[6] = 0.5;  // the hinge (after the free joint's six dofs)
    int touching = 0;
    for (int k = 0; k < 240; ++k) {
      state.body_f[6 * 5 + 0] = 2;  // a push on the first sensor, welded to the base
      state.body_f[6 * 5 + 5] = 0.3;
      pipeline.collide(state, contacts);
      for (int c = 0; c < contacts.contact_count; ++c) touching += contacts.contact_body_b[c] == 4;
      solver.step(state, state, control, contacts, 1.0 / 240);
    }
    EXPECT_GT(touching, 0) << "the welded tool touched the ground";
    return state;
  };
  const State welded = run(true), plain = run(false);
  for (size_t k = 0; k < welded.joint_q.size(); ++k) EXPECT_NEAR(welded.joint_q[k], plain.joint_q[k], 1e-9) << k;
  for (size_t k = 0; k < welded.body_q.size(); ++k) EXPECT_NEAR(welded.body_q[k], plain.body_q[k], 1e-9) << k;
  for (size_t k = 0; k < welded.body_qd.size(); ++k) EXPECT_NEAR(welded.body_qd[k], plain.body_qd[k], 1e-8) << k;
  EXPECT_LT(welded.body_q[2], 0.2);  // the arm fell 0.8 m onto the ground
}

// many worlds of the arm, whose welded bodies are numbered between their links: each world's bodies
// written at their own rows whether streamed around the caches (stream_body_output_above = 0) or stored
// through them, as the arm stepped with its Fixed links in the kernels writes them
TEST(WeldFixedJoints, ManyWorldsWriteEachBodyAtItsRow) {
  for (const Precision precision : {Precision::Float64, Precision::Float32}) {
    ModelBuilder batch(Vec3(0, 0, -9.81));
    batch.set_precision(precision);
    batch.replicate(arm_with_fixed_links(), 37, Vec3(1, 0, 0));
    const Model model = batch.finalize();
    auto run = [&](bool weld, std::int64_t stream_above) {
      SolverFeatherstoneSettings settings;
      settings.weld_fixed_joints = weld;
      settings.stream_body_output_above = stream_above;
      SolverFeatherstone solver(model, settings);
      CollisionPipeline pipeline(model);
      Contacts contacts = pipeline.contacts();
      State state = model.state();
      const Control control = model.control();
      for (int k = 0; k < 60; ++k) {
        pipeline.collide(state, contacts);
        solver.step(state, state, control, contacts, 1.0 / 240);
      }
      return state;
    };
    constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
    const State streamed = run(true, 0), stored = run(true, kNever), plain = run(false, kNever);
    EXPECT_EQ(std::memcmp(streamed.body_q.data(), stored.body_q.data(), stored.body_q.size() * sizeof(Scalar)), 0);
    EXPECT_EQ(std::memcmp(streamed.body_qd.data(), stored.body_qd.data(), stored.body_qd.size() * sizeof(Scalar)), 0);
    const double tolerance = precision == Precision::Float64 ? 1e-9 : 1e-4;
    for (size_t k = 0; k < plain.body_q.size(); ++k) EXPECT_NEAR(stored.body_q[k], plain.body_q[k], tolerance) << k;
    for (size_t k = 0; k < plain.body_qd.size(); ++k)
      EXPECT_NEAR(stored.body_qd[k], plain.body_qd[k], 10 * tolerance) << k;
  }
}

}  // namespace
}  // namespace novaphy
