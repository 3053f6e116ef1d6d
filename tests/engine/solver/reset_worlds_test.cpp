// Model::reset_worlds and restart_worlds with the collide and step after it: the worlds reset and only they, and a
// reset world stepping bit for bit as it would from a fresh start (no warm start, no kept factor of its past)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "engine/import/mjcf_import.h"
#include "engine/model/body_kinematics.h"
#include "solver_test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

using solver_test::Scene;
using solver_test::world_rows;
using solver_test::world_state;

constexpr int kWorlds = 5;

// `file` replicated into kWorlds worlds in `precision`, with the keyframe "settled": the robot's coordinates after
// `settle` steps alone (its feet or fingers touching, so a reset world's first contacts meet its old ones' keys)
ModelBuilder worlds_of(const std::string& file, Precision precision, int settle) {
  ModelBuilder robot;
  import_mjcf(robot, file);
  Scene alone(robot);
  alone.run(settle * 0.002, 0.002);
  robot.add_keyframe("settled", alone.state.joint_q);
  ModelBuilder worlds;
  worlds.set_precision(precision);
  worlds.replicate(robot, kWorlds);
  return worlds;
}

// random commands for every actuator, the same sequence for every scene given the same seed
void command(Control& control, std::mt19937& rng) {
  std::uniform_real_distribution<Scalar> u(-1, 1);
  for (Scalar& c : control.actuator_ctrl) c = u(rng);
}

TEST(ResetWorlds, WritesTheWorldsGivenAndNoOther) {
  Scene scene(worlds_of(NOVAPHY_SCENE_DIR "/quadruped.xml", Precision::Float64, 100));
  scene.state.body_f.assign(scene.state.body_f.size(), 0.5);
  scene.run(0.1, 0.002);
  const State before = scene.state;
  const int settled = scene.model.keyframe("settled");
  scene.model.reset_worlds(scene.state, {3, 1, 3}, settled);
  const State fresh = scene.model.state("settled");
  for (int w = 0; w < kWorlds; ++w) {
    const bool reset = w == 1 || w == 3;
    EXPECT_EQ(scene.state.world_reset[w], reset ? 1 : 0) << "world " << w;
    std::vector<Scalar> expected = world_state(scene.model, reset ? fresh : before, w);
    if (reset) {
      const std::vector<Scalar> f = world_rows(scene.model, fresh.body_f, scene.model.body_count, w);
      std::fill(expected.end() - static_cast<std::ptrdiff_t>(f.size()), expected.end(), 0);
    }
    EXPECT_EQ(world_state(scene.model, scene.state, w), expected) << "world " << w;
  }
  // to the initial coordinates at rest
  scene.model.reset_worlds(scene.state, {0});
  EXPECT_EQ(world_rows(scene.model, scene.state.joint_q, scene.model.joint_coord_count, 0),
            world_rows(scene.model, scene.model.joint_q0, scene.model.joint_coord_count, 0));
  for (const Scalar v : world_rows(scene.model, scene.state.joint_qd, scene.model.joint_dof_count, 0)) EXPECT_EQ(v, 0);
  // a step writes 0
  scene.run(0.002, 0.002);
  for (int w = 0; w < kWorlds; ++w) EXPECT_EQ(scene.state.world_reset[w], 0);
}

// `scene` stepped `steps` steps of dt 2 ms under random commands from seed `seed`
void run_commanded(Scene& scene, int steps, unsigned seed) {
  std::mt19937 rng(seed);
  for (int k = 0; k < steps; ++k) {
    command(scene.control, rng);
    scene.run(0.002, 0.002);
  }
}

TEST(ResetWorlds, AResetWorldStepsBitForBitAsFromAFreshStart) {
  for (const char* file : {NOVAPHY_SCENE_DIR "/quadruped.xml", NOVAPHY_TEST_MODEL_DIR "/arm.xml"}) {
    bool history_shows = false;  // in some world of either precision (else the test shows nothing)
    for (const Precision precision : {Precision::Float64, Precision::Float32}) {
      SCOPED_TRACE(std::string(file) + (precision == Precision::Float32 ? " float32" : " float64"));
      const ModelBuilder builder = worlds_of(file, precision, 150);
      // two scenes with one history (the same commands), then worlds 1 and 3 reset: by reset_worlds, and by hand
      // (the same arrays, world_reset left 0: the steps after it use the worlds' warm starts)
      Scene reset(builder), by_hand(builder);
      run_commanded(reset, 60, 7);
      run_commanded(by_hand, 60, 7);
      reset.model.reset_worlds(reset.state, {1, 3}, reset.model.keyframe("settled"));
      by_hand.state = reset.state;
      std::fill(by_hand.state.world_reset.begin(), by_hand.state.world_reset.end(), 0);
      // a fresh start from the reset state: a new pipeline, contacts buffer and solver
      Scene fresh(builder);
      fresh.state = reset.state;
      for (Scene* scene : {&reset, &by_hand, &fresh}) run_commanded(*scene, 30, 11);
      for (const int w : {1, 3}) {
        const std::vector<Scalar> expected = world_state(fresh.model, fresh.state, w);
        EXPECT_EQ(world_state(reset.model, reset.state, w), expected) << "world " << w;
        history_shows |= world_state(by_hand.model, by_hand.state, w) != expected;
      }
    }
    EXPECT_TRUE(history_shows) << file << ": the worlds' history changes nothing: the test shows nothing";
  }
}

// a world the divergence guard restarts (on_divergence Reset, at the keyframe "settled") steps on as from a fresh
// solver and pipeline: none of its contacts' warm starts from before it diverged
TEST(ResetWorlds, AWorldTheDivergenceGuardResetsStepsOnAsFromAFreshStart) {
  for (const Precision precision : {Precision::Float64, Precision::Float32}) {
    SCOPED_TRACE(precision == Precision::Float32 ? "float32" : "float64");
    const ModelBuilder builder = worlds_of(NOVAPHY_SCENE_DIR "/quadruped.xml", precision, 150);
    SolverFeatherstoneSettings settings;
    settings.on_divergence = DivergencePolicy::Reset;
    Scene wild(builder, settings), fresh(builder, settings);
    wild.solver.set_reset_keyframe("settled");
    run_commanded(wild, 60, 7);
    ASSERT_EQ(wild.model.articulation_world(2), 2);
    wild.state.joint_qd[wild.model.articulation(2).qd_begin()] = 2e6;
    wild.run(0.002, 0.002);
    ASSERT_EQ(wild.solver.diverged()[2], 1);
    EXPECT_EQ(wild.state.world_reset, (std::vector<std::uint8_t>{0, 0, 1, 0, 0}));
    fresh.state = wild.state;
    run_commanded(wild, 30, 11);
    run_commanded(fresh, 30, 11);
    EXPECT_EQ(world_state(wild.model, wild.state, 2), world_state(fresh.model, fresh.state, 2));
  }
}

// restart_worlds: a world started from coordinates and velocities written into the state (a pose turned about z,
// moving), its bodies by FK of them as a new state's, every other world untouched; its quaternion normalised
TEST(RestartWorlds, StartsTheWorldsFromTheirOwnCoordinatesAndVelocities) {
  Scene scene(worlds_of(NOVAPHY_SCENE_DIR "/quadruped.xml", Precision::Float64, 100));
  scene.state.body_f.assign(scene.state.body_f.size(), 0.5);
  scene.run(0.1, 0.002);
  const State before = scene.state;
  const Model& model = scene.model;
  const ArticulationView art = model.articulation(2);  // (one articulation a world: world 2's)
  ASSERT_EQ(model.articulation_world(2), 2);
  ASSERT_EQ(art.type(0), JointType::Free);
  std::vector<Scalar> q(model.joint_q0.begin() + art.q_begin(),
                        model.joint_q0.begin() + art.q_begin() + art.coord_count());
  const Scalar half_turn = 0.3;  // the root turned 0.6 rad about z: [x y z w], given at norm 2
  q[3] = 0, q[4] = 0, q[5] = 2 * std::sin(half_turn), q[6] = 2 * std::cos(half_turn);
  std::vector<Scalar> qd(art.dof_count());
  for (int k = 0; k < art.dof_count(); ++k) qd[k] = 0.1 * (k + 1);
  std::copy(q.begin(), q.end(), scene.state.joint_q.begin() + art.q_begin());
  std::copy(qd.begin(), qd.end(), scene.state.joint_qd.begin() + art.qd_begin());
  model.restart_worlds(scene.state, {2});
  // the quaternion normalised (to its last bit, which is the normalisation's own); the oracle: a new state of the
  // model with world 2's coordinates as restart_worlds left them and its velocities, FK of all
  q[5] = std::sin(half_turn), q[6] = std::cos(half_turn);
  for (int k = 0; k < art.coord_count(); ++k)
    EXPECT_NEAR(scene.state.joint_q[art.q_begin() + k], q[k], 1e-15) << "coordinate " << k;
  State fresh = model.state();
  std::copy_n(scene.state.joint_q.begin() + art.q_begin(), art.coord_count(), fresh.joint_q.begin() + art.q_begin());
  std::copy(qd.begin(), qd.end(), fresh.joint_qd.begin() + art.qd_begin());
  bodies_from_joints(model, fresh);
  for (int w = 0; w < kWorlds; ++w) {
    EXPECT_EQ(scene.state.world_reset[w], w == 2 ? 1 : 0) << "world " << w;
    EXPECT_EQ(world_state(model, scene.state, w), world_state(model, w == 2 ? fresh : before, w)) << "world " << w;
  }
}

TEST(RestartWorlds, BadValuesAreNamedAndNothingIsWritten) {
  Scene scene(worlds_of(NOVAPHY_SCENE_DIR "/quadruped.xml", Precision::Float64, 10));
  const Model& model = scene.model;
  const ArticulationView art = model.articulation(1);
  const State good = scene.state;
  auto expect_refused = [&](const std::function<void(State&)>& spoil, const std::string& text) {
    scene.state = good;
    spoil(scene.state);
    const State spoiled = scene.state;
    EXPECT_NOVAPHY_ERROR(model.restart_worlds(scene.state, {0, 1}), text);
    EXPECT_EQ(std::memcmp(scene.state.joint_q.data(), spoiled.joint_q.data(), spoiled.joint_q.size() * sizeof(Scalar)),
              0);  // (bits: a NaN is not equal to itself)
    EXPECT_EQ(scene.state.body_q, spoiled.body_q);
    EXPECT_EQ(scene.state.world_reset, spoiled.world_reset);
  };
  const int q = art.q_begin() + 2, qd = art.qd_begin() + 7, quat = art.q_begin() + 3;
  expect_refused([&](State& s) { s.joint_q[q] = NAN; },
                 "restart_worlds: joint_q[" + std::to_string(q) + "] (world 1) is not finite: nan");
  expect_refused([&](State& s) { s.joint_qd[qd] = INFINITY; },
                 "restart_worlds: joint_qd[" + std::to_string(qd) + "] (world 1) is not finite: inf");
  expect_refused([&](State& s) { std::fill_n(s.joint_q.begin() + quat, 4, 0.0); },
                 "restart_worlds: the quaternion joint_q[" + std::to_string(quat) + ":" + std::to_string(quat + 4) +
                     "] of joint '" + model.joint_name[art.joint_begin] + "' (world 1) is zero");
  EXPECT_NOVAPHY_ERROR(model.restart_worlds(scene.state, {1, 5}),
                       "restart_worlds: worlds[1] = 5 is not a world of the model (0 .. 4)");
}

}  // namespace
}  // namespace novaphy
