#include "engine/solver/blocks/blocks.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>

#include "engine/import/mjcf_import.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support.h"

namespace novaphy {
namespace {

constexpr Scalar kDt = 0.005;

ModelBuilder quadruped(bool floor) {
  ModelBuilder robot;
  ImportOptions options;
  options.static_shapes = floor;
  import_mjcf(robot, NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  return robot;
}

ModelBuilder scene(const char* name) {
  ModelBuilder robot;
  import_mjcf(robot, std::string(NOVAPHY_SCENE_DIR "/") + name);
  return robot;
}

// the robot replicated into `worlds` worlds at one place (worlds do not touch each other), in `precision`
Model replicated(const ModelBuilder& robot, int worlds, Precision precision) {
  ModelBuilder batch(robot.gravity());
  batch.set_precision(precision);
  batch.replicate(robot, worlds);
  return batch.finalize();
}

// world w's masses and inertias scaled by its own factor, its coordinates nudged: every world differs;
// every fifth world (a floating robot) lifted by 10 cm, so it has fewer contacts than its block-mates
// while it falls
Scalar world_scale(int w) { return 1 + 0.4 * std::sin(1.7 * w); }
void randomize_world(Model& model, State& state, int w, int first_body, int body_count, int first_coord,
                     int coord_count) {
  for (int b = first_body; b < first_body + body_count; ++b) {
    model.body_mass[b] *= world_scale(w);
    for (int k = 0; k < 9; ++k) model.body_inertia[9 * b + k] *= world_scale(w);
  }
  for (int c = 0; c < coord_count; ++c) state.joint_q[first_coord + c] += 0.05 * std::cos(0.3 * w + c);
  if (w % 5 == 0) state.joint_q[first_coord + 2] += 0.1;
}

// `steps` steps of the model from `state`, with collisions when `collide`
void step(const Model& model, State& state, int steps, const SolverFeatherstoneSettings& settings = {},
          bool collide = true) {
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstone solver(model, settings);
  const Control control = model.control();
  for (int k = 0; k < steps; ++k) {
    if (collide) pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, kDt);
  }
}

Scalar max_relative_difference(const std::vector<Scalar>& a, const std::vector<Scalar>& b) {
  Scalar worst = 0, scale = 1;
  for (size_t k = 0; k < b.size(); ++k) scale = std::max(scale, std::abs(b[k]));
  for (size_t k = 0; k < b.size(); ++k) worst = std::max(worst, std::abs(a[k] - b[k]));
  return worst / scale;
}

// the batched kernels against the scalar ones, step for step, without contacts (the order of
// contacts found in a tie follows the rounding of the poses, and PGS sweeps rows in that order);
// H by CRBA or, with `tile_gemm`, by the product of link Jacobians on both sides
Scalar batched_against_scalar(const Model& model, int steps, bool tile_gemm = false) {
  State batched = model.state(), scalar = model.state();
  std::mt19937 rng(7);
  test::randomize_state(model, batched, rng, true);
  scalar.assign(batched);
  SolverFeatherstoneSettings settings;
  settings.use_tile_gemm = tile_gemm;
  step(model, batched, steps, settings, false);
  settings.use_batch_kernels = false;
  step(model, scalar, steps, settings, false);
  return std::max({max_relative_difference(batched.joint_q, scalar.joint_q),
                   max_relative_difference(batched.joint_qd, scalar.joint_qd),
                   max_relative_difference(batched.body_q, scalar.body_q),
                   max_relative_difference(batched.body_qd, scalar.body_qd)});
}
Scalar batched_against_scalar(const ModelBuilder& robot, int worlds, Precision precision, int steps,
                              bool tile_gemm = false) {
  return batched_against_scalar(replicated(robot, worlds, precision), steps, tile_gemm);
}

TEST(ArticulationBatches, GroupsReplicatedWorldsIntoBlocks) {
  const Model model = replicated(quadruped(false), 37, Precision::Float64);
  SolverFeatherstone solver(model);
  ASSERT_NE(solver.batches(), nullptr);
  EXPECT_EQ(solver.batches()->group_count(), 1);
  const int lanes = solver.batches()->lanes();
  EXPECT_EQ(solver.batches()->block_count(), (37 + lanes - 1) / lanes);
  for (int a = 0; a < model.articulation_count; ++a) EXPECT_TRUE(solver.batches()->active(a));
}

TEST(ArticulationBatches, Float64MatchesTheScalarKernels) {
  // limits on (the quadruped's), drives and springs, applied wrenches
  EXPECT_LT(batched_against_scalar(scene("chain15.xml"), 5, Precision::Float64, 200), 1e-10);
  EXPECT_LT(batched_against_scalar(scene("ball_chain30.xml"), 3, Precision::Float64, 200), 1e-10);
  EXPECT_LT(batched_against_scalar(quadruped(false), 5, Precision::Float64, 200), 1e-10);
  // every joint type, rotated joint frames, offset centres of mass, applied wrenches; one world per
  // block with its other lanes padded
  std::mt19937 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const Model tree = test::random_builder_tree(rng, 2 + trial, 1 + trial % 3);
    EXPECT_LT(batched_against_scalar(tree, 50), 1e-9) << "trial " << trial;
  }
}

TEST(ArticulationBatches, TiledMassMatrixMatchesTheScalarProduct) {
  // use_tile_gemm: tiles padded at every dof count (chain15: 15 columns on its last link), branches
  EXPECT_LT(batched_against_scalar(scene("chain15.xml"), 3, Precision::Float64, 200, true), 1e-10);
  EXPECT_LT(batched_against_scalar(quadruped(false), 3, Precision::Float64, 200, true), 1e-10);
  std::mt19937 rng(4);
  for (int trial = 0; trial < 5; ++trial) {
    const Model tree = test::random_builder_tree(rng, 3 + 2 * trial, 1 + trial % 2);
    EXPECT_LT(batched_against_scalar(tree, 50, true), 1e-9) << "trial " << trial;
  }
}

TEST(ArticulationBatches, LimitRowsSolvedInBlocksMatchTheScalarRows) {
  // the hanging quadruped pushed against its limits: every leg joint beyond its range at the start.
  // World 2's first leg joint has no limit: its lane of that joint's rows stays off and its kept
  // impulse 0, the other worlds' limit impulses kept beside it
  Model model = replicated(quadruped(false), 12, Precision::Float64);
  State batched = model.state();
  for (int j = 0; j < model.joint_count; ++j) {
    if (model.joint_type[j] != static_cast<int>(JointType::Revolute)) continue;
    const int g = model.joint_qd_start[j];
    batched.joint_q[model.joint_q_start[j]] = model.joint_limit_upper[g] + 0.05;
    batched.joint_qd[g] = 1;
  }
  const int unlimited = model.joint_qd_start[model.articulation(2).joint_begin + 1];
  model.joint_limit_lower[unlimited] = -std::numeric_limits<Scalar>::infinity();
  model.joint_limit_upper[unlimited] = std::numeric_limits<Scalar>::infinity();
  State scalar = model.state();
  scalar.assign(batched);
  // two sweeps: the impulses each step starts from (the last step's kept) show in the result
  SolverFeatherstoneSettings settings;
  settings.num_iterations = 2;
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstone on(model, settings);
  settings.use_batch_kernels = false;
  SolverFeatherstone off(model, settings);
  const Control control = model.control();
  for (int k = 0; k < 100; ++k) {
    on.step(batched, batched, control, contacts, kDt);
    off.step(scalar, scalar, control, contacts, kDt);
  }
  EXPECT_LT(max_relative_difference(batched.joint_q, scalar.joint_q), 1e-10);
  EXPECT_LT(max_relative_difference(batched.joint_qd, scalar.joint_qd), 1e-10);
  // the limits held: every leg joint back within its range, less the slop and a step's motion
  for (int j = 0; j < model.joint_count; ++j) {
    if (model.joint_type[j] != static_cast<int>(JointType::Revolute)) continue;
    const int g = model.joint_qd_start[j];
    EXPECT_LT(batched.joint_q[model.joint_q_start[j]], model.joint_limit_upper[g] + 0.02) << "joint " << j;
  }
}

TEST(ArticulationBatches, Float32StaysCloseToFloat64) {
  EXPECT_LT(batched_against_scalar(scene("chain15.xml"), 5, Precision::Float32, 100), 1e-3);
  EXPECT_LT(batched_against_scalar(quadruped(false), 5, Precision::Float32, 100), 1e-3);
}

// torso height of the quadruped standing on its floor after `seconds`
Scalar standing_height(Precision precision, bool batched, Scalar seconds, Scalar pgs_tolerance = 0) {
  const Model model = replicated(quadruped(true), 3, precision);
  State state = model.state();
  SolverFeatherstoneSettings settings;
  settings.use_batch_kernels = batched;
  settings.pgs_tolerance = pgs_tolerance;
  step(model, state, static_cast<int>(seconds / kDt), settings);
  return state.body_q[2];  // body 0 (torso), z up
}

TEST(ArticulationBatches, QuadrupedStandsWhereTheScalarKernelsStandIt) {
  const Scalar scalar = standing_height(Precision::Float64, false, 2);
  EXPECT_GT(scalar, 0.3);
  EXPECT_NEAR(standing_height(Precision::Float64, true, 2), scalar, 1e-6);
  EXPECT_NEAR(standing_height(Precision::Float32, true, 2), scalar, 1e-4);
}

TEST(ArticulationBatches, APgsToleranceStandsTheQuadrupedWhereEverySweepDoes) {
  // the sweeps stopped once no row's velocity moves by more than 1e-5 m/s: the height it stands at
  // moves by less than a micrometre, on the scalar and the batched path alike
  const Scalar every_sweep = standing_height(Precision::Float64, false, 2);
  EXPECT_NEAR(standing_height(Precision::Float64, false, 2, 1e-5), every_sweep, 1e-6);
  EXPECT_NEAR(standing_height(Precision::Float64, true, 2, 1e-5), every_sweep, 1e-6);
  EXPECT_NEAR(standing_height(Precision::Float32, true, 2, 1e-5), every_sweep, 1e-4);
}

TEST(ArticulationBatches, ContactRowsSolvedInBlocksMatchTheScalarRows) {
  // six standing quadrupeds, two of them dropped from 15 cm onto a bouncy floor, and a box falling
  // onto world 0's torso: that contact joins two moving articulations, so world 0 and the box stay on
  // the scalar path while the other worlds' limit and contact rows are solved in their blocks. Every
  // step both solvers start from the same state and contacts (warm starts included)
  ModelBuilder batch(quadruped(true).gravity());
  batch.replicate(quadruped(true), 6);
  ModelBuilder box;
  const int box_body = box.add_body(RigidBody::from_box(2, Vec3::Constant(0.1)));
  box.add_shape_box(box_body, Vec3::Constant(0.1));
  batch.add_builder(box, Transform{Vec3(0.05, 0, 0.75)}, 0);
  Model model = batch.finalize();
  for (Scalar& e : model.shape_restitution) e = 0.3;
  const int nq = (model.joint_coord_count - 7) / 6, box_index = model.body_count - 1;
  State batched = model.state();
  for (const int w : {2, 3}) batched.joint_q[w * nq + 2] += 0.15;
  State scalar = model.state();
  SolverFeatherstoneSettings settings;
  settings.friction_smoothing = 0.5;
  SolverFeatherstone on(model, settings);
  settings.use_batch_kernels = false;
  SolverFeatherstone off(model, settings);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts(), contacts_scalar = pipeline.contacts();
  const Control control = model.control();
  Scalar worst_qd = 0, worst_impulse = 0;
  int box_on_torso = 0;
  for (int k = 0; k < 150; ++k) {
    pipeline.collide(batched, contacts);
    scalar.assign(batched);
    contacts_scalar = contacts;
    on.step(batched, batched, control, contacts, kDt);
    off.step(scalar, scalar, control, contacts_scalar, kDt);
    worst_qd = std::max(worst_qd, max_relative_difference(batched.joint_qd, scalar.joint_qd));
    worst_impulse =
        std::max(worst_impulse, max_relative_difference(contacts.contact_impulse, contacts_scalar.contact_impulse));
    for (int c = 0; c < contacts.contact_count; ++c)
      box_on_torso += (contacts.contact_body_a[c] == box_index && contacts.contact_body_b[c] >= 0) ||
                      (contacts.contact_body_b[c] == box_index && contacts.contact_body_a[c] >= 0);
  }
  EXPECT_GT(box_on_torso, 0);

  // (the two paths differ in rounding only: 2e-15 seen)
  EXPECT_LT(worst_qd, 1e-12);
  EXPECT_LT(worst_impulse, 1e-12);
  // every world still standing: the torso above its legs' length
  for (int w = 0; w < 6; ++w) EXPECT_GT(batched.joint_q[w * nq + 2], 0.3) << "world " << w;
}

std::string first_difference(const State& batch, int w, const State& alone, int nq, int nv, int nb) {
  auto same = [](const Scalar* a, const Scalar* b, int n) { return std::memcmp(a, b, n * sizeof(Scalar)) == 0; };
  if (!same(&batch.joint_q[w * nq], alone.joint_q.data(), nq)) return "joint_q";
  if (!same(&batch.joint_qd[w * nv], alone.joint_qd.data(), nv)) return "joint_qd";
  if (!same(&batch.body_q[w * nb * 7], alone.body_q.data(), 7 * nb)) return "body_q";
  if (!same(&batch.body_qd[w * nb * 6], alone.body_qd.data(), 6 * nb)) return "body_qd";
  return "";
}

// every shape of condim 6 (each contact's rows one friction cone: kernels/pgs.h, solve_contact_cone)
void make_cones(Model& model) {
  for (int s = 0; s < model.shape_count; ++s) {
    model.shape_condim[s] = 6;
    model.shape_mu_torsion[s] = 0.02;
    model.shape_mu_rolling[s] = 0.01;
  }
}

void expect_each_world_equals_it_alone(Precision precision, Scalar pgs_tolerance = 0, bool cones = false) {
  // (with a pgs_tolerance each world stops its sweeps on its own, whatever its block-mates need)
  constexpr int kWorlds = 1000, kSteps = 60;
  SolverFeatherstoneSettings settings;
  settings.pgs_tolerance = pgs_tolerance;
  const ModelBuilder robot = quadruped(true);
  Model model = replicated(robot, kWorlds, precision);
  if (cones) make_cones(model);
  const int nb = model.body_count / kWorlds, nq = model.joint_coord_count / kWorlds,
            nv = model.joint_dof_count / kWorlds;
  State state = model.state();
  for (int w = 0; w < kWorlds; ++w) randomize_world(model, state, w, w * nb, nb, w * nq, nq);
  step(model, state, kSteps, settings);
  for (int w = 0; w < kWorlds; ++w) {
    Model alone = replicated(robot, 1, precision);
    if (cones) make_cones(alone);
    State s = alone.state();
    randomize_world(alone, s, w, 0, nb, 0, nq);
    step(alone, s, kSteps, settings);
    ASSERT_EQ(first_difference(state, w, s, nq, nv, nb), "") << "world " << w << " differs from itself alone";
  }
}

TEST(ArticulationBatches, EveryWorldOfAThousandEqualsItselfSteppedAloneFloat64) {
  expect_each_world_equals_it_alone(Precision::Float64);
}
TEST(ArticulationBatches, EveryWorldOfAThousandEqualsItselfSteppedAloneFloat32) {
  expect_each_world_equals_it_alone(Precision::Float32);
}
TEST(ArticulationBatches, EveryWorldOfAThousandEqualsItselfSteppedAloneWithAPgsTolerance) {
  expect_each_world_equals_it_alone(Precision::Float32, 1e-4);
  expect_each_world_equals_it_alone(Precision::Float64, 1e-6);
}
// each lane's cone projection stops its Newton steps on its own too
TEST(ArticulationBatches, EveryWorldOfAThousandEqualsItselfSteppedAloneWithFrictionCones) {
  expect_each_world_equals_it_alone(Precision::Float32, 1e-4, true);
  expect_each_world_equals_it_alone(Precision::Float64, 0, true);
}

// all threads, and more threads than the machine has cores: the last eighth of each parallel loop is dealt
// to whichever thread is free, so which thread steps those blocks changes from step to step
TEST(ArticulationBatches, OneThreadAndAllThreadsAreBitIdentical) {
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    Model model = replicated(quadruped(true), 300, precision);
    State initial = model.state();
    const int nb = model.body_count / 300, nq = model.joint_coord_count / 300;
    for (int w = 0; w < 300; ++w) randomize_world(model, initial, w, w * nb, nb, w * nq, nq);
    State one = model.state();
    one.assign(initial);
    SolverFeatherstoneSettings settings;
    settings.num_threads = 1;
    step(model, one, 50, settings);
    for (const int threads : {0, 3, 5}) {
      State all = model.state();
      all.assign(initial);
      settings.num_threads = threads;
      step(model, all, 50, settings);
      EXPECT_EQ(std::memcmp(one.joint_q.data(), all.joint_q.data(), one.joint_q.size() * sizeof(Scalar)), 0)
          << threads << " threads";
      EXPECT_EQ(std::memcmp(one.body_qd.data(), all.body_qd.data(), one.body_qd.size() * sizeof(Scalar)), 0)
          << threads << " threads";
    }
  }
}

// worlds of two robots added in turn: a block's worlds' bodies are not numbered one after another, so
// its body_q and body_qd are written a body at a time instead of streamed as one span; each world still
// equals itself stepped alone (whose block streams), bit for bit
TEST(ArticulationBatches, BlocksOfInterleavedWorldsWriteTheirBodiesAsContiguousOnesDo) {
  constexpr int kWorlds = 20;
  const ModelBuilder legs = quadruped(false), chain = scene("chain15.xml");
  ModelBuilder batch(legs.gravity());
  for (int w = 0; w < kWorlds; ++w) batch.add_builder(w % 2 == 0 ? legs : chain, Transform{}, w);
  const Model model = batch.finalize();
  State state = model.state();
  step(model, state, 20, {}, false);
  int body = 0;
  for (int w = 0; w < kWorlds; ++w) {
    ModelBuilder one(legs.gravity());
    one.add_builder(w % 2 == 0 ? legs : chain);
    const Model alone = one.finalize();
    State s = alone.state();
    step(alone, s, 20, {}, false);
    ASSERT_EQ(std::memcmp(&state.body_q[7 * body], s.body_q.data(), s.body_q.size() * sizeof(Scalar)), 0)
        << "world " << w;
    ASSERT_EQ(std::memcmp(&state.body_qd[6 * body], s.body_qd.data(), s.body_qd.size() * sizeof(Scalar)), 0)
        << "world " << w;
    body += alone.body_count;
  }
}

// worlds with the same parameters share one copy of them (it stays in cache); one world changed makes
// every block keep its own. The worlds that did not change step to the same bits either way
TEST(ArticulationBatches, IdenticalWorldsShareOneCopyOfTheirParameters) {
  constexpr int kWorlds = 64, kChanged = 40;
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    const Model same = replicated(quadruped(true), kWorlds, precision);
    Model changed = replicated(quadruped(true), kWorlds, precision);
    const int nb = changed.body_count / kWorlds;
    changed.body_mass[kChanged * nb] *= 1.5;
    State a = same.state(), b = changed.state();
    step(same, a, 30);
    step(changed, b, 30);
    const SolverFeatherstone shared(same), own(changed);
    const int blocks = own.batches()->block_count();
    // each block's copy: at least mass, com and inertia of every link in every lane
    const std::size_t block_bytes =
        static_cast<std::size_t>(10) * nb * own.batches()->lanes() * (precision == Precision::Float32 ? 4 : 8);
    EXPECT_GE(own.memory_bytes() - shared.memory_bytes(), (blocks - 1) * block_bytes);
    const int nq = changed.joint_coord_count / kWorlds;
    for (int w = 0; w < kWorlds; ++w) {
      const bool equal = std::memcmp(&a.joint_q[w * nq], &b.joint_q[w * nq], nq * sizeof(Scalar)) == 0;
      EXPECT_EQ(equal, w != kChanged) << "world " << w;
    }
  }
}

// body output streamed around the caches (stream_body_output_above = 0) or stored through them: the
// same bits, with contacts
TEST(ArticulationBatches, StreamedBodyOutputEqualsStoredOutput) {
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    const Model model = replicated(quadruped(true), 50, precision);
    State streamed = model.state(), stored = model.state();
    SolverFeatherstoneSettings settings;
    settings.stream_body_output_above = 0;
    step(model, streamed, 30, settings);
    settings.stream_body_output_above = std::numeric_limits<std::int64_t>::max();
    step(model, stored, 30, settings);
    EXPECT_EQ(std::memcmp(streamed.body_q.data(), stored.body_q.data(), stored.body_q.size() * sizeof(Scalar)), 0);
    EXPECT_EQ(std::memcmp(streamed.body_qd.data(), stored.body_qd.data(), stored.body_qd.size() * sizeof(Scalar)), 0);
    EXPECT_EQ(std::memcmp(streamed.joint_q.data(), stored.joint_q.data(), stored.joint_q.size() * sizeof(Scalar)), 0);
  }
}

// a step with every articulation in a block and every row solved there runs each block's dynamics,
// rows and integration in turn; with settings.profile_stages the solver also times each block's stages, the
// same schedule and arithmetic: bit-identical states and impulses, with contacts, limits, PD drives, an applied
// wrench, angular damping and a change of update_mass_matrix_interval all in play. One at a time, the blocks
// also write each world's new state as they step it; under on_divergence Raise they leave that to a pass after
// the guard: the same states
TEST(ArticulationBatches, BlocksSteppedProfiledOrStoredAfterTheGuardGiveTheSameBits) {
  for (const Precision precision : {Precision::Float32, Precision::Float64}) {
    constexpr int kWorlds = 100;
    Model model = replicated(quadruped(true), kWorlds, precision);
    State initial = model.state();
    const int nb = model.body_count / kWorlds, nq = model.joint_coord_count / kWorlds;
    for (int w = 0; w < kWorlds; ++w) randomize_world(model, initial, w, w * nb, nb, w * nq, nq);
    Control control = model.control();
    for (int k = 6; k < model.joint_dof_count; k += 5) {
      control.joint_target_ke[k] = 20;
      control.joint_target_kd[k] = 0.5;
      control.joint_target_pos[k] = 0.1;
    }
    State blocks = model.state(), timed = model.state(), after_guard = model.state();
    blocks.assign(initial);
    timed.assign(initial);
    after_guard.assign(initial);
    blocks.body_f[6 * 3 + 2] = timed.body_f[6 * 3 + 2] = after_guard.body_f[6 * 3 + 2] = 5;
    SolverFeatherstoneSettings settings;
    settings.angular_damping = 0.5;
    SolverFeatherstone one_at_a_time(model, settings);
    settings.on_divergence = DivergencePolicy::Raise;
    SolverFeatherstone stored_after_guard(model, settings);
    settings.on_divergence = DivergencePolicy::Flag;
    settings.profile_stages = true;
    SolverFeatherstone profiled(model, settings);
    // the mass matrix refactored every step (one at a time: in scratch, kept for no later step), then
    // every third (kept in the blocks)
    auto interval = [&](int k) { return k < 20 ? 1 : 3; };
    CollisionPipeline pipeline(model);
    Contacts contacts_blocks = pipeline.contacts(), contacts_profiled = pipeline.contacts(),
             contacts_after_guard = pipeline.contacts();
    int contacts_seen = 0;
    for (int k = 0; k < 40; ++k) {
      pipeline.collide(blocks, contacts_blocks);
      pipeline.collide(timed, contacts_profiled);
      pipeline.collide(after_guard, contacts_after_guard);
      one_at_a_time.settings.update_mass_matrix_interval = profiled.settings.update_mass_matrix_interval =
          stored_after_guard.settings.update_mass_matrix_interval = interval(k);
      one_at_a_time.step(blocks, blocks, control, contacts_blocks, kDt);
      profiled.step(timed, timed, control, contacts_profiled, kDt);
      stored_after_guard.step(after_guard, after_guard, control, contacts_after_guard, kDt);
      contacts_seen += contacts_blocks.contact_count;
    }
    EXPECT_GT(contacts_seen, 0);
    EXPECT_EQ(profiled.stage_seconds().steps, 40);
    auto same = [](const std::vector<Scalar>& a, const std::vector<Scalar>& b) {
      return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Scalar)) == 0;
    };
    EXPECT_TRUE(same(blocks.joint_q, timed.joint_q));
    EXPECT_TRUE(same(blocks.joint_qd, timed.joint_qd));
    EXPECT_TRUE(same(blocks.body_q, timed.body_q));
    EXPECT_TRUE(same(blocks.body_qd, timed.body_qd));
    EXPECT_TRUE(same(contacts_blocks.contact_impulse, contacts_profiled.contact_impulse));
    for (const auto field : {&State::joint_q, &State::joint_qd, &State::body_q, &State::body_qd})
      EXPECT_TRUE(same(blocks.*field, after_guard.*field));
  }
}

// solvers stepped on the threads of a user's own parallel loop (more threads than the machine's cores
// here): each uses its scratch of thread 0 and steps as it does alone, bit for bit
TEST(ArticulationBatches, SolversSteppedInsideAUsersParallelLoopStepAsAlone) {
  constexpr int kSolvers = 4;
  Model model = replicated(quadruped(true), 40, Precision::Float32);
  State initial = model.state();
  const int nb = model.body_count / 40, nq = model.joint_coord_count / 40;
  for (int w = 0; w < 40; ++w) randomize_world(model, initial, w, w * nb, nb, w * nq, nq);
  std::vector<State> alone(kSolvers, model.state()), inside(kSolvers, model.state());
  for (int k = 0; k < kSolvers; ++k) {
    alone[k].assign(initial);
    inside[k].assign(initial);
    alone[k].joint_qd[k] = inside[k].joint_qd[k] = 0.1 * (k + 1);  // each solver its own trajectory
    step(model, alone[k], 20);
  }
#pragma omp parallel for num_threads(kSolvers)
  for (int k = 0; k < kSolvers; ++k) step(model, inside[k], 20);
  for (int k = 0; k < kSolvers; ++k) {
    EXPECT_EQ(std::memcmp(alone[k].joint_q.data(), inside[k].joint_q.data(), alone[k].joint_q.size() * sizeof(Scalar)),
              0)
        << "solver " << k;
    EXPECT_EQ(std::memcmp(alone[k].body_qd.data(), inside[k].body_qd.data(), alone[k].body_qd.size() * sizeof(Scalar)),
              0)
        << "solver " << k;
  }
}

}  // namespace
}  // namespace novaphy
