#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "solver_test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

using namespace solver_test;

// ---- determinism: same inputs, bit-identical states ----

// 9 sprung quadrupeds and a pile of boxes: contacts between robots, boxes and the ground
ModelBuilder contact_rich_scene(int first_robot = 0) {
  ModelBuilder builder;
  builder.add_plane(Vec3::UnitZ(), 0);
  ImportOptions options;
  options.static_shapes = false;
  for (int k = first_robot; k < first_robot + 9; ++k) {
    options.xform.p = Vec3(0.7 * (k % 3), 0.5 * (k / 3), 0.3);
    import_mjcf(builder, NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  }
  for (int k = 0; k < 10; ++k) add_box(builder, Vec3(0.1 * k, 0.2 * (k % 3), 1.0 + 0.3 * k), 0.1, 1, 0.7);
  builder.set_gravity(Vec3(0, 0, -9.81));
  return builder;
}

std::size_t state_hash(const State& state) {
  std::size_t h = 1469598103934665603ull;
  for (const auto* field : {&state.joint_q, &state.joint_qd, &state.body_q, &state.body_qd})
    for (const Scalar x : *field) h = (h ^ std::hash<Scalar>{}(x)) * 1099511628211ull;
  return h;
}

std::size_t run_hash(const ModelBuilder& builder, int threads, int steps = 1000) {
  SolverFeatherstoneSettings settings;
  settings.num_threads = threads;
  Scene scene(builder, settings);
  scene.run(steps * 0.005, 0.005);
  return state_hash(scene.state);
}

TEST(Determinism, RunToRunAndAnyThreadCount) {
  const ModelBuilder builder = contact_rich_scene();
  const std::size_t one = run_hash(builder, 1);
  EXPECT_EQ(run_hash(builder, 1), one);
  EXPECT_EQ(run_hash(builder, 2), one);
  EXPECT_EQ(run_hash(builder, 3), one);
}

// a robot's trajectory does not depend on where its articulation sits in the model
TEST(Determinism, ArticulationPositionInTheModel) {
  ModelBuilder alone;
  alone.add_plane(Vec3::UnitZ(), 0);
  ImportOptions options;
  options.static_shapes = false;
  options.xform.p = Vec3(0, 0, 0.3);
  const MujocoImport a = import_mjcf(alone, NOVAPHY_SCENE_DIR "/quadruped.xml", options);

  ModelBuilder crowd;
  crowd.add_plane(Vec3::UnitZ(), 0);
  for (int k = 1; k <= 3; ++k) {
    ImportOptions far = options;
    far.xform.p = Vec3(5.0 * k, 0, 0.3);
    import_mjcf(crowd, NOVAPHY_SCENE_DIR "/quadruped.xml", far);
  }
  const MujocoImport b = import_mjcf(crowd, NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  alone.set_gravity(Vec3(0, 0, -9.81));
  crowd.set_gravity(Vec3(0, 0, -9.81));

  Scene first(alone), second(crowd);
  first.run(2, 0.005);
  second.run(2, 0.005);
  const int nq = first.model.joint_coord_count, nv = first.model.joint_dof_count;
  const std::vector<Scalar> q1(first.state.joint_q.begin(), first.state.joint_q.end());
  const std::vector<Scalar> q2(second.state.joint_q.begin() + b.q_begin, second.state.joint_q.begin() + b.q_begin + nq);
  const std::vector<Scalar> v1(first.state.joint_qd.begin(), first.state.joint_qd.end());
  const std::vector<Scalar> v2(second.state.joint_qd.begin() + b.qd_begin,
                               second.state.joint_qd.begin() + b.qd_begin + nv);
  EXPECT_EQ(q1, q2);
  EXPECT_EQ(v1, v2);
  EXPECT_EQ(a.q_begin, 0);
}

TEST(Determinism, RestoredCheckpointContinuesIdentically) {
  // warm starting keeps impulses in the contacts buffer and the solver, outside the state: off here
  SolverFeatherstoneSettings settings;
  settings.use_warmstarting = false;
  Scene scene(contact_rich_scene(), settings);
  scene.run(0.5, 0.005);
  State checkpoint = scene.model.state();
  checkpoint.assign(scene.state);
  scene.run(0.5, 0.005);
  const std::size_t straight = state_hash(scene.state);
  scene.state.assign(checkpoint);
  scene.run(0.5, 0.005);
  EXPECT_EQ(state_hash(scene.state), straight);

  ModelBuilder other;
  add_box(other, Vec3::Zero());
  const Model small = other.finalize();
  State wrong = small.state();
  EXPECT_NOVAPHY_ERROR(wrong.assign(scene.state), "assign: the other state belongs to a model with");
}

// ---- extremes ----

// a chain of revolute box links (one per mass) about Z, joined end to end, horizontal at q = 0, no XML
ModelBuilder revolute_chain(const std::vector<Scalar>& masses, const Vec3& half_extents) {
  ModelBuilder builder;
  int parent = -1;
  for (const Scalar m : masses) {
    const int link = builder.add_body(RigidBody::from_box(m, half_extents));
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.parent_xform.p = parent < 0 ? Vec3::Zero() : Vec3(half_extents.x(), 0, 0);
    options.child_xform.p = Vec3(-half_extents.x(), 0, 0);
    builder.add_joint_revolute(parent, link, options);
    parent = link;
  }
  return builder;
}

// n links 0.1 m long of 0.1 kg
ModelBuilder long_chain(int n) { return revolute_chain(std::vector<Scalar>(n, 0.1), Vec3(0.05, 0.01, 0.01)); }

// 1000 links: the solver takes ABA (O(n)) by default and agrees with CRBA + Cholesky (O(n^3)) over
// ten steps; half a second later the chain has fallen, finite
TEST(Extremes, ThousandLinkChainStepsOnAbaAndAgreesWithCrba) {
  const int n = 1000;
  SolverFeatherstoneSettings crba_settings;
  crba_settings.aba_min_dofs = n + 1;
  Scene aba(long_chain(n)), crba(long_chain(n), crba_settings);
  ASSERT_GE(n, aba.solver.settings.aba_min_dofs);
  aba.run(0.01, 0.001);
  crba.run(0.01, 0.001);
  Scalar largest = 0;
  for (const Scalar v : crba.state.joint_qd) largest = std::max(largest, std::abs(v));
  // relative 4e-7 seen: the dense factor of this H loses digits to its conditioning (kappa ~ n^4)
  EXPECT_LT(max_difference(aba.state.joint_qd, crba.state.joint_qd), 1e-5 * largest);
  aba.run(0.49, 0.001);
  for (const Scalar q : aba.state.joint_q) ASSERT_TRUE(std::isfinite(q));
  const Vec3 tip = aba.position(n - 1);
  EXPECT_LT(tip.y(), -1.0);  // the chain fell under gravity
}

// a pendulum of links 0.5 m long with the given masses, horizontal at q = 0, no damping
ModelBuilder pendulum_chain(const std::vector<Scalar>& masses) {
  return revolute_chain(masses, Vec3(0.25, 0.02, 0.02));
}

// largest |E(t) - E(0)| over a run, relative to the energy scale m g l of the first link
Scalar energy_drift(Scene& scene, Scalar seconds, Scalar dt) {
  const Scalar e0 = eval_energy(scene.model, scene.state), scale = scene.model.body_mass[0] * 9.81 * 0.5;
  Scalar worst = 0;
  scene.run(seconds, dt, [&] { worst = std::max(worst, std::abs(eval_energy(scene.model, scene.state) - e0)); });
  return worst / scale;
}

// links of 1 kg alternating with links a thousand and a million times lighter: the light links do
// not change the motion (measured drift 0.157 m g l for both ratios in 2 s at dt = 1 ms)
TEST(Extremes, AdjacentLinkMassRatios) {
  std::vector<Scalar> drift;
  for (const Scalar ratio : {1e-3, 1e-6}) {
    Scene scene(pendulum_chain({1, ratio, 1, ratio}), no_damping());
    drift.push_back(energy_drift(scene, 2, 1e-3));
    for (const Scalar q : scene.state.joint_q) ASSERT_TRUE(std::isfinite(q)) << "ratio " << ratio;
  }
  EXPECT_LT(drift[0], 0.25);
  EXPECT_LT(std::abs(drift[1] - drift[0]), 0.01);
}

// 1e5 steps of a double pendulum released horizontal, no damping: semi-implicit Euler keeps its
// energy within 2 % of m g l at dt = 0.1 ms (measured 1.3 %; at dt = 1 ms it loses 24 % in 10 s)
TEST(Extremes, ConservativeDoublePendulumEnergy) {
  Scene scene(pendulum_chain({1, 1}), no_damping());
  EXPECT_LT(energy_drift(scene, 10, 1e-4), 0.02);
}

// 100 rad/s about the intermediate axis, 20 000 steps of 0.1 ms without gravity: the spin flips
// (Dzhanibekov) either way; its energy drifts by the given share at the given coriolis_implicitness
Scalar spin_energy_drift(Scalar implicitness, Scalar* lowest_spin) {
  ModelBuilder builder(Vec3::Zero());
  builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.1, 0.2)));  // y: the intermediate axis
  SolverFeatherstoneSettings settings = no_damping();
  settings.coriolis_implicitness = implicitness;
  Scene scene(builder, settings);
  scene.state.joint_qd[0] = 0.01;
  scene.state.joint_qd[1] = 100;
  const Scalar e0 = eval_energy(scene.model, scene.state);
  Scalar worst = 0;
  *lowest_spin = 100;
  scene.run(2, 1e-4, [&] {
    worst = std::max(worst, std::abs(eval_energy(scene.model, scene.state) / e0 - 1));
    const Transform X = Transform::from_array(&scene.state.body_q[0]);
    *lowest_spin = std::min(*lowest_spin, (X.q.conjugate() * Eigen::Map<const Vec3>(&scene.state.joint_qd[0])).y());
  });
  return worst;
}

// explicit: 7.6 % energy gained; the linearised midpoint: 9e-6 (measured); asserted: 1 %
TEST(Extremes, SpinAboutTheIntermediateAxisFlipsAndKeepsItsEnergy) {
  Scalar lowest = 0;
  EXPECT_LT(spin_energy_drift(0.5, &lowest), 0.01);
  EXPECT_LT(lowest, -90);  // the body-frame spin turned over
  EXPECT_GT(spin_energy_drift(0, &lowest), 0.05);
  EXPECT_LT(lowest, -90);
}

// the 15-link chain (bench/scenes/chain15.xml, no floor) falling from horizontal for 10 s at
// dt = 1/120 s: its whipping tip blows up with explicit Coriolis forces (the guard flags it), and
// stays finite with the linearised midpoint
int chain_diverged_steps(Scalar implicitness, Scalar* energy_change) {
  ModelBuilder builder;
  ImportOptions options;
  options.static_shapes = false;
  import_mjcf(builder, NOVAPHY_SCENE_DIR "/chain15.xml", options);
  SolverFeatherstoneSettings settings = no_damping();
  settings.coriolis_implicitness = implicitness;
  Scene scene(builder, settings);
  const Scalar e0 = eval_energy(scene.model, scene.state);
  int diverged = 0;
  scene.run(10, 1.0 / 120, [&] { diverged += scene.solver.diverged()[0]; });
  *energy_change = eval_energy(scene.model, scene.state) - e0;
  return diverged;
}

TEST(Extremes, WhippingChainAtLargeSteps) {
  Scalar change = 0;
  EXPECT_GT(chain_diverged_steps(0, &change), 0);
  EXPECT_EQ(chain_diverged_steps(0.5, &change), 0);
  EXPECT_LT(change, 0);  // joint damping (0.05 in the file) only takes energy out
}

TEST(Extremes, QuaternionNormsAfterAMillionSteps) {
  ModelBuilder builder(Vec3::Zero());
  builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.1, 0.2)));
  Scene scene(builder, no_damping());
  scene.state.joint_qd[0] = 3;
  scene.state.joint_qd[1] = 7;
  scene.state.joint_qd[2] = 1;
  scene.run(100, 1e-4);
  EXPECT_LT(std::abs(Eigen::Map<const Eigen::Matrix<Scalar, 4, 1>>(&scene.state.joint_q[3]).norm() - 1), 1e-12);
}

// kp = 1e6 on a 10 g link at dt = 1/120 s: the implicit drive reaches its target without overshoot
TEST(Extremes, StiffPdDriveOnALightLink) {
  ModelBuilder builder;
  const int link = builder.add_body(RigidBody::from_box(0.01, Vec3(0.05, 0.01, 0.01)));
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(-0.05, 0, 0);
  builder.add_joint_revolute(-1, link, options);
  Scene scene(builder);
  scene.control.joint_target_ke[0] = 1e6;
  scene.control.joint_target_kd[0] = 10;
  scene.control.joint_target_pos[0] = 0.5;
  Scalar highest = 0;
  scene.run(1, kDt, [&] { highest = std::max(highest, scene.state.joint_q[0]); });
  EXPECT_LT(std::abs(scene.state.joint_q[0] - 0.5), 1e-6);
  EXPECT_LT(highest, 0.5 + 1e-6);
}

// a pendulum swung 0.6 s with dt from 1/30 s to 0.1 ms against dt = 10 us: first order, the
// angle error below 1.5 dt rad (measured 1.1-1.23 dt)
TEST(Extremes, TimeStepsFromAThirtiethToTenMicroseconds) {
  auto swing = [](Scalar dt) {
    Scene scene(pendulum_chain({1}), no_damping());
    scene.run(0.6, dt);
    return scene.state.joint_q[0];
  };
  const Scalar reference = swing(1e-5);
  ASSERT_TRUE(std::isfinite(reference));
  for (const Scalar dt : {1.0 / 30, 1.0 / 120, 1e-3, 1e-4}) EXPECT_LT(std::abs(swing(dt) - reference), 1.5 * dt);
}

// ten 0.4 m boxes stacked: they stand 10 s, the worst moving 2.7 cm
TEST(Extremes, TenBoxStack) {
  ModelBuilder builder;
  builder.add_ground_plane();
  std::vector<int> boxes;
  for (int k = 0; k < 10; ++k) boxes.push_back(add_box(builder, Vec3(0, 0.2 + 0.4 * k, 0)));
  Scene scene(builder);
  scene.run(10);
  for (int k = 0; k < 10; ++k)
    EXPECT_LT((scene.position(boxes[k]) - Vec3(0, 0.2 + 0.4 * k, 0)).norm(), 0.05) << "box " << k;
}

// a 100 kg box on a 1 kg box: 100 PGS iterations keep it on top for 10 s (4 cm of creep); the
// default 20 do not, the heavy box creeps off within 10 s (a limit of Gauss-Seidel at this mass ratio)
TEST(Extremes, HeavyBoxOnALightOne) {
  auto heavy_after = [](int iterations) {
    ModelBuilder builder;
    builder.add_ground_plane();
    add_box(builder, Vec3(0, 0.2, 0), 0.2, 1);
    const int heavy = add_box(builder, Vec3(0, 0.6, 0), 0.2, 100);
    SolverFeatherstoneSettings settings;
    settings.num_iterations = iterations;
    Scene scene(builder, settings);
    scene.run(10);
    return scene.position(heavy);
  };
  const Vec3 held = heavy_after(100);
  EXPECT_LT(std::abs(held.y() - 0.6), 0.005);
  EXPECT_LT(std::hypot(held.x(), held.z()), 0.05);
  EXPECT_LT(heavy_after(20).y(), 0.5);  // the documented limit: fallen off
}

}  // namespace
}  // namespace novaphy
