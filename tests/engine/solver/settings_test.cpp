#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "solver_test_support.h"

namespace novaphy {
namespace {

using namespace solver_test;

// ---- every setting changes the computation ----

Scalar tower_top_error(int iterations) {
  ModelBuilder builder;
  builder.add_ground_plane();
  int top = -1;
  for (int k = 0; k < 5; ++k) top = add_box(builder, Vec3(0, 0.2 + 0.4 * k, 0));
  SolverFeatherstoneSettings settings;
  settings.num_iterations = iterations;
  Scene scene(builder, settings);
  scene.run(1);
  return std::abs(scene.position(top).y() - 1.8);
}

TEST(SolverFeatherstoneSettingsEffect, NumIterations) { EXPECT_GT(tower_top_error(1), 5 * tower_top_error(30)); }

// a box started 2 cm inside the ground is pushed out until the slop is left
Scalar rest_depth(const std::function<void(SolverFeatherstoneSettings&)>& configure, Scalar seconds = 3) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int box = add_box(builder, Vec3(0, 0.18, 0));
  SolverFeatherstoneSettings settings;
  configure(settings);
  Scene scene(builder, settings);
  scene.run(seconds);
  return 0.2 - scene.position(box).y();
}

TEST(SolverFeatherstoneSettingsEffect, LinearSlop) {
  EXPECT_NEAR(rest_depth([](auto& s) { s.linear_slop = 0.001; }), 0.001, 1e-4);
  EXPECT_NEAR(rest_depth([](auto& s) { s.linear_slop = 0.01; }), 0.01, 1e-4);
}

TEST(SolverFeatherstoneSettingsEffect, Erp) {
  // one step removes about erp of the penetration beyond the slop
  for (const Scalar erp : {0.1, 0.5}) {
    const Scalar depth = rest_depth([&](auto& s) { s.erp = erp; }, kDt);
    const Scalar expected = 0.02 - erp * (0.02 - 0.001);
    EXPECT_NEAR(depth, expected, 0.1 * (0.02 - expected)) << "erp " << erp;
  }
}

TEST(SolverFeatherstoneSettingsEffect, Cfm) {
  // a soft contact settles deeper by cfm * lambda * dt / erp, lambda = m g dt / 4 per corner
  const Scalar stiff = rest_depth([](auto& s) { s.cfm = 1e-6; });
  const Scalar soft = rest_depth([](auto& s) { s.cfm = 1.0; });
  const Scalar lambda = 9.81 * kDt / 4;
  EXPECT_NEAR(soft - stiff, 1.0 * lambda * kDt / 0.2, 0.1 * lambda * kDt / 0.2);
}

// after a second of normal solving, iterations stop: only warm-started impulses hold the box up (a contact's rows
// start from all of their impulses, converged or not)
Scalar drop_without_iterations(bool use_warmstarting, Scalar factor) {
  ModelBuilder builder;
  builder.add_ground_plane();
  const int box = add_box(builder, Vec3(0, 0.2, 0));
  Scene scene(builder);
  scene.run(1);
  const Scalar y = scene.position(box).y();
  scene.solver.settings.num_iterations = 0;
  scene.solver.settings.use_warmstarting = use_warmstarting;
  scene.solver.settings.warmstarting_factor = factor;
  scene.solver.settings.divergence_depth = 10;  // (without iterations it sinks on purpose, over 1 m)
  scene.run(0.5);
  return y - scene.position(box).y();
}

// the same with an arm held at its joint's lower limit: a limit row starts from warmstarting_factor of its last
// impulse once its world's sweeps ran out (here every step without iterations); the angle it sags by
Scalar sag_without_iterations(Scalar factor) {
  ModelBuilder builder;
  JointOptions hinge;
  hinge.dof.axis = Vec3::UnitZ();
  hinge.dof.limit_lower = 0;
  hinge.dof.limit_upper = 1;
  const int arm = builder.add_body(RigidBody::from_box(1, Vec3(0.2, 0.02, 0.02)));
  hinge.child_xform.p = Vec3(-0.2, 0, 0);  // the hinge at the arm's end: gravity turns it to its lower limit
  builder.add_joint_revolute(-1, arm, hinge);
  Scene scene(builder);
  scene.run(1);
  const Scalar q = scene.state.joint_q[0];
  scene.solver.settings.num_iterations = 0;
  scene.solver.settings.warmstarting_factor = factor;
  scene.solver.settings.divergence_depth = 10;  // (without iterations it sinks on purpose, over 1 m)
  scene.run(0.5);
  return q - scene.state.joint_q[0];
}

TEST(SolverFeatherstoneSettingsEffect, WarmstartingFactor) {
  EXPECT_LT(sag_without_iterations(1.0), 1e-3);
  EXPECT_GT(sag_without_iterations(0.5), 0.01);
  EXPECT_LT(drop_without_iterations(true, 0.5), 1e-3);  // not a contact's
}

TEST(SolverFeatherstoneSettingsEffect, UseWarmstarting) { EXPECT_GT(drop_without_iterations(false, 1.0), 0.5); }

TEST(SolverFeatherstoneSettingsEffect, RestitutionThreshold) {
  for (const Scalar threshold : {0.2, 10.0}) {
    ModelBuilder builder;
    builder.add_ground_plane(0, material(0.5, 0.8));
    const int ball = builder.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0, 1.1, 0)});
    builder.add_shape_sphere(ball, 0.1, material(0.5, 0.8));
    SolverFeatherstoneSettings settings;
    settings.restitution_threshold = threshold;
    Scene scene(builder, settings);
    Scalar rebound = 0;
    scene.run(0.8, kDt, [&] { rebound = std::max(rebound, scene.velocity(ball).y()); });
    // impact at sqrt(2 g) = 4.4 m/s: above the low threshold it bounces at 0.8 of that; below the
    // high one only the position correction of the impact's penetration lifts it (erp, see README)
    if (threshold < 4)
      EXPECT_GT(rebound, 3.0);
    else
      EXPECT_LT(rebound, 0.1 * 0.8 * 4.4);
  }
}

TEST(SolverFeatherstoneSettingsEffect, AngularDamping) {
  for (const Scalar damping : {0.0, 0.5}) {
    ModelBuilder builder(Vec3::Zero());
    builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.2, 0.3)));
    SolverFeatherstoneSettings settings;
    settings.angular_damping = damping;
    Scene scene(builder, settings);
    scene.state.joint_qd[1] = 3.0;  // spin about the y principal axis
    scene.run(1);
    EXPECT_NEAR(scene.state.joint_qd[1], 3.0 * std::pow(1 - damping * kDt, 120), 1e-9) << "damping " << damping;
  }
}

// a contact-free double pendulum: chaotic enough that any change in H shows
std::vector<Scalar> double_pendulum(const std::function<void(SolverFeatherstoneSettings&)>& configure,
                                    Scalar seconds = 2) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  const int b = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.25, 0, 0);
  builder.add_joint_revolute(-1, a, options);
  options.parent_xform.p = Vec3(0.25, 0, 0);
  builder.add_joint_revolute(a, b, options);
  SolverFeatherstoneSettings settings = no_damping();
  configure(settings);
  Scene scene(builder, settings);
  scene.run(seconds);
  return scene.state.joint_q;
}

TEST(SolverFeatherstoneSettingsEffect, UpdateMassMatrixInterval) {
  const auto every = double_pendulum([](auto&) {}, 0.5);
  const auto reused = double_pendulum([](auto& s) { s.update_mass_matrix_interval = 4; }, 0.5);
  EXPECT_GT(max_difference(every, reused), 1e-6);  // a stale H changes the trajectory ...
  EXPECT_LT(max_difference(every, reused), 0.2);   // ... but only a little at this cadence
}

TEST(SolverFeatherstoneSettingsEffect, UseTileGemmGivesTheSameMassMatrix) {
  const auto crba = double_pendulum([](auto&) {});
  const auto gemm = double_pendulum([](auto& s) { s.use_tile_gemm = true; });
  EXPECT_LT(max_difference(crba, gemm), 1e-9);
  const auto scalar_gemm = double_pendulum([](auto& s) {
    s.use_tile_gemm = true;
    s.use_batch_kernels = false;
  });
  EXPECT_LT(max_difference(crba, scalar_gemm), 1e-9);
}

TEST(SolverFeatherstoneSettingsEffect, FuseCholeskyGivesTheSameSolution) {
  const auto fused = double_pendulum([](auto&) {});
  const auto split = double_pendulum([](auto& s) { s.fuse_cholesky = false; });
  EXPECT_LT(max_difference(fused, split), 1e-12);
}

// the ABA path (O(n) factor and solves) against CRBA + Cholesky on the standing quadruped: contacts,
// limits, springs, damping and PD drives all go through M^-1
TEST(SolverFeatherstoneSettingsEffect, AbaMinDofsGivesTheSameTrajectory) {
  auto run = [](int aba_min_dofs) {
    ModelBuilder builder;
    import_mjcf(builder, NOVAPHY_SCENE_DIR "/quadruped.xml");
    SolverFeatherstoneSettings settings;
    settings.aba_min_dofs = aba_min_dofs;
    Scene scene(builder, settings);
    for (int k = 0; k < scene.model.joint_dof_count; ++k) {
      scene.control.joint_target_ke[k] = 20;
      scene.control.joint_target_kd[k] = 1;
      scene.control.joint_target_pos[k] = 0.3;
    }
    scene.run(1.0, 0.005);
    EXPECT_GT(scene.contacts.contact_count, 0);
    return scene.state.joint_q;
  };
  const std::vector<Scalar> crba = run(1000), aba = run(0);
  EXPECT_LT(max_difference(crba, aba), 1e-8);
}

// a box sliding diagonally to the tangent axes: the circular cone decelerates it at mu g, box
// friction clamps each tangent to mu lambda_n and decelerates it at sqrt(2) mu g
TEST(SolverFeatherstoneSettingsEffect, FrictionSmoothing) {
  for (const Scalar smoothing : {0.0, 1.0}) {
    ModelBuilder builder;
    builder.add_ground_plane(0, material(0.5));
    const int box = add_box(builder, Vec3(0, 0.2, 0), 0.2, 1, 0.5);
    SolverFeatherstoneSettings settings = no_damping();
    settings.friction_smoothing = smoothing;
    settings.pgs_tolerance = 0;  // the cone's own direction: sweeps to a fixed point
    Scene scene(builder, settings);
    const Vec3 diagonal = Vec3(1, 0, 1).normalized();
    Eigen::Map<Vec3>(&scene.state.joint_qd[3]) = 3.0 * diagonal;  // Free dofs [w; v]
    scene.run(kDt);
    const Scalar v0 = scene.velocity(box).dot(diagonal);
    scene.run(0.25);
    const Scalar deceleration = (v0 - scene.velocity(box).dot(diagonal)) / 0.25;
    const Scalar expected = (smoothing == 0 ? std::sqrt(2.0) : 1.0) * 0.5 * 9.81;
    EXPECT_NEAR(deceleration, expected, 0.05 * expected) << "friction_smoothing " << smoothing;
    EXPECT_LT(scene.velocity(box).cross(diagonal).norm(), 1e-6);  // keeps its direction
  }
}

TEST(SolverFeatherstoneSettingsEffect, ProfileStagesTimesEachStageOnlyWhenOn) {
  ModelBuilder builder;
  builder.add_ground_plane();
  add_box(builder, Vec3(0, 0.19, 0));
  Scene scene(builder);
  scene.run(0.1);
  EXPECT_EQ(scene.solver.stage_seconds().steps, 0);
  EXPECT_EQ(scene.solver.stage_seconds().dynamics, 0);
  scene.solver.settings.profile_stages = true;
  scene.run(0.1);
  const SolverStageSeconds& t = scene.solver.stage_seconds();
  EXPECT_EQ(t.steps, 12);
  for (const double seconds : {t.dynamics, t.contact_rows, t.solve, t.integrate}) EXPECT_GT(seconds, 0);
  scene.solver.reset_stage_seconds();
  EXPECT_EQ(scene.solver.stage_seconds().steps, 0);
}

TEST(SolverFeatherstoneSettingsEffect, CountSerialTimeSplitsEachStepOnlyWhenOn) {
  ModelBuilder builder;
  builder.add_ground_plane();
  add_box(builder, Vec3(0, 0.19, 0));
  Scene scene(builder);
  scene.run(0.1);
  EXPECT_EQ(scene.solver.serial_seconds().steps, 0);
  EXPECT_EQ(scene.solver.serial_seconds().step, 0);
  scene.solver.settings.count_serial_time = true;
  scene.run(0.1);
  const SerialSeconds& t = scene.solver.serial_seconds();
  EXPECT_EQ(t.steps, 12);
  EXPECT_GT(t.parallel, 0);
  EXPECT_LT(t.parallel, t.step);  // the parallel work is a part of the steps' time
  EXPECT_GT(t.share(), 0);
  EXPECT_LT(t.share(), 1);
  scene.solver.reset_serial_seconds();
  EXPECT_EQ(scene.solver.serial_seconds().steps, 0);
  EXPECT_EQ(scene.solver.serial_seconds().share(), 0);
}

}  // namespace
}  // namespace novaphy
