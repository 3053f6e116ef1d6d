#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "engine/threads/exclusive_call.h"
#include "solver_test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

using namespace solver_test;

// the finite checks of a state long enough to be split over threads still name the first bad entry
TEST(SolverFeatherstoneErrors, ANonFiniteEntryOfALargeStateIsNamedOnAnyThreadCount) {
  ModelBuilder world, builder;
  add_box(world, Vec3(0, 0.5, 0));
  builder.replicate(world, 12000);  // 84000 coordinates, 72000 body_f entries
  const Model model = builder.finalize();
  for (const int threads : {1, 2}) {
    SolverFeatherstoneSettings settings;
    settings.num_threads = threads;
    SolverFeatherstone solver(model, settings);
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    State state = model.state();
    const Control control = model.control();
    state.body_f[6 * 11999 + 4] = std::numeric_limits<Scalar>::infinity();
    state.body_f[6 * 11999 + 5] = std::nan("");
    EXPECT_NOVAPHY_ERROR(solver.step(state, state, control, contacts, kDt), "body_f[71998] is not finite: inf");
    state.body_f = model.state().body_f;
    state.joint_q[7 * 9000 + 2] = std::nan("");
    EXPECT_NOVAPHY_ERROR(solver.step(state, state, control, contacts, kDt), "joint_q[63002] is not finite: nan");
  }
}

// the PD targets enter a step only through a nonzero gain: without one, non-finite targets are not read (the
// steps equal those with finite targets, on the batched and the scalar path); with one, the first is named
// and nothing is written
TEST(SolverFeatherstoneErrors, PdTargetsAreCheckedWhenAGainReadsThem) {
  ModelBuilder builder;
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.child_xform.p = Vec3(0, 0.25, 0);  // each hinge at the top of its link
  const int upper = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  builder.add_joint_revolute(-1, upper, options);
  const int lower = builder.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  options.parent_xform.p = Vec3(0, -0.25, 0);
  builder.add_joint_revolute(upper, lower, options);
  for (const bool batched : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = batched;
    Scene finite(builder, settings), bad(builder, settings);
    finite.state.joint_q[0] = bad.state.joint_q[0] = 0.5;
    bad.control.joint_target_pos[0] = std::nan("");
    bad.control.joint_target_vel[1] = std::numeric_limits<Scalar>::infinity();
    finite.run(0.5);
    bad.run(0.5);
    EXPECT_EQ(bad.state.joint_q, finite.state.joint_q) << "batched " << batched;
    EXPECT_EQ(bad.state.joint_qd, finite.state.joint_qd) << "batched " << batched;
    EXPECT_EQ(bad.state.body_q, finite.state.body_q) << "batched " << batched;

    const State before = bad.state;
    bad.control.joint_target_kd[1] = 1;
    EXPECT_NOVAPHY_ERROR(bad.solver.step(bad.state, bad.state, bad.control, bad.contacts, kDt),
                         "joint_target_pos[0] is not finite: nan");
    bad.control.joint_target_pos[0] = 0;
    EXPECT_NOVAPHY_ERROR(bad.solver.step(bad.state, bad.state, bad.control, bad.contacts, kDt),
                         "joint_target_vel[1] is not finite: inf");
    EXPECT_EQ(bad.state.joint_q, before.joint_q);
    EXPECT_EQ(bad.state.body_q, before.body_q);
  }
}

TEST(SolverFeatherstoneErrors, BadStepArguments) {
  ModelBuilder builder;
  builder.add_ground_plane();
  add_box(builder, Vec3(0, 0.5, 0));
  Scene scene(builder);
  const State before = scene.state;
  for (const Scalar dt : {0.0, -0.01, std::nan("")})
    EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, dt),
                         "dt must be finite and > 0");

  ModelBuilder other;
  other.add_ground_plane();
  add_box(other, Vec3(0, 0.5, 0));
  add_box(other, Vec3(0, 1.5, 0));
  Scene foreign(other);
  EXPECT_NOVAPHY_ERROR(scene.solver.step(foreign.state, scene.state, scene.control, scene.contacts, kDt),
                       "state or control from another model");
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, foreign.contacts, kDt),
                       "contacts buffer is from another model");
  EXPECT_NOVAPHY_ERROR(scene.pipeline.collide(scene.state, foreign.contacts),
                       "contacts buffer was not made by this pipeline");

  scene.solver.settings.num_iterations = -1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.num_iterations must be >= 0, got -1");
  scene.solver.settings = {};
  scene.solver.settings.erp = 1.5;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.erp must be in [0, 1], got 1.5");
  scene.solver.settings = {};
  scene.solver.settings.update_mass_matrix_interval = 0;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.update_mass_matrix_interval must be >= 1, got 0");
  scene.solver.settings = {};
  scene.solver.settings.aba_min_dofs = -1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.aba_min_dofs must be >= 0, got -1");
  scene.solver.settings = {};
  scene.solver.settings.stream_body_output_above = -1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.stream_body_output_above must be >= 0 bytes, got -1");
  scene.solver.settings = {};
  scene.solver.settings.coriolis_implicitness = 1.5;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "settings.coriolis_implicitness must be in [0, 1], got 1.5");
  scene.solver.settings = {};
  scene.control.joint_f[2] = std::nan("");
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                       "joint_f[2] is not finite: nan");
  // nothing was written by the failed steps
  EXPECT_EQ(scene.state.joint_q, before.joint_q);
  EXPECT_EQ(scene.state.body_q, before.body_q);

  // a velocity no double can hold after the step: the step raises and leaves the state as it was
  scene.control.joint_f[2] = 0;
  scene.control.joint_f[3] = 1e308;
  scene.state.joint_qd[3] = 1e308;
  const State fast = scene.state;
  scene.solver.settings.on_divergence = DivergencePolicy::Raise;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, 1.0),
                       "step diverged in articulation 0");
  EXPECT_EQ(scene.state.joint_q, fast.joint_q);
  EXPECT_EQ(scene.state.joint_qd, fast.joint_qd);

  SolverFeatherstoneSettings bad;
  bad.friction_smoothing = -1;
  EXPECT_NOVAPHY_ERROR(SolverFeatherstone(scene.model, bad), "settings.friction_smoothing must be in [0, 1], got -1");
  bad = {};
  bad.pgs_tolerance = std::nan("");
  EXPECT_NOVAPHY_ERROR(SolverFeatherstone(scene.model, bad), "settings.pgs_tolerance must be in [0, 1000000], got nan");
}

// a mass matrix that is not positive definite in one world (its link made massless on the Model, as no
// builder call allows) raises; that world is left as it was, and under Raise every world is
TEST(SolverFeatherstoneErrors, AFailedMassMatrixLeavesItsWorldAsItWas) {
  for (const DivergencePolicy policy : {DivergencePolicy::Flag, DivergencePolicy::Raise}) {
    Model model = pendulum_worlds(Precision::Float32).finalize();
    model.body_mass[1] = 0;
    std::fill_n(model.body_inertia.begin() + 9, 9, 0);
    SolverFeatherstoneSettings settings;
    settings.on_divergence = policy;
    SolverFeatherstone solver(model, settings);
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    State state = model.state();
    const State before = state;
    EXPECT_NOVAPHY_ERROR(solver.step(state, state, model.control(), contacts, kDt),
                         "articulation 1: mass matrix is not positive definite at dof 1");
    EXPECT_EQ(state.joint_q[1], before.joint_q[1]);
    EXPECT_EQ(state.joint_qd[1], before.joint_qd[1]);
    for (int m = 0; m < 7; ++m) EXPECT_EQ(state.body_q[7 + m], before.body_q[7 + m]);
    if (policy == DivergencePolicy::Raise) {
      EXPECT_EQ(state.joint_q, before.joint_q);
      EXPECT_EQ(state.joint_qd, before.joint_qd);
      EXPECT_EQ(state.body_q, before.body_q);
      EXPECT_EQ(state.body_qd, before.body_qd);
    } else {  // the others were stepped as they went (the one exception to "nothing is written")
      EXPECT_NE(state.joint_qd[0], before.joint_qd[0]);
    }
  }
}

// a world whose input is not finite is left as it was and the step raises naming the entry, whichever input it
// is (the step finds it from the world's output, which a non-finite input reaches: a wrench or a gain that is not
// finite is nonzero, so it is applied); under Raise nothing is written, under Flag and Reset every other world is
// stepped, its block-mates too; on the blocks and on the dense route, and the next step goes on
TEST(SolverFeatherstoneErrors, AWorldWithNonFiniteInputIsLeftAsItWas) {
  constexpr int kWorlds = 40, kBad = 38;  // world 38 shares its block with world 39
  const Scalar nan = std::nan(""), inf = std::numeric_limits<Scalar>::infinity();
  struct Poison {
    const char* message;
    std::function<void(State&, Control&)> set;
  };
  const Poison poisons[] = {
      {"joint_q[38] is not finite: nan", [&](State& s, Control&) { s.joint_q[kBad] = nan; }},
      {"joint_qd[38] is not finite: inf", [&](State& s, Control&) { s.joint_qd[kBad] = inf; }},
      {"joint_f[38] is not finite: nan", [&](State&, Control& c) { c.joint_f[kBad] = nan; }},
      {"body_f[230] is not finite: inf", [&](State& s, Control&) { s.body_f[6 * kBad + 2] = inf; }},
      {"actuator_ctrl[38] is not finite: nan", [&](State&, Control& c) { c.actuator_ctrl[kBad] = nan; }},
      {"joint_target_kd[38] is not finite: nan", [&](State&, Control& c) { c.joint_target_kd[kBad] = nan; }},
      {"joint_target_pos[38] is not finite: nan", [&](State&, Control& c) {
         c.joint_target_ke[kBad] = 10;
         c.joint_target_pos[kBad] = nan;
       }}};
  auto same_bits = [](Scalar a, Scalar b) { return std::memcmp(&a, &b, sizeof(a)) == 0; };
  for (const Precision precision : {Precision::Float32, Precision::Float64})
    for (const bool batched : {true, false})
      for (const DivergencePolicy policy : {DivergencePolicy::Flag, DivergencePolicy::Reset, DivergencePolicy::Raise})
        for (const Poison& poison : poisons) {
          ModelBuilder builder = pendulum_worlds(precision, kWorlds);
          for (int w = 0; w < kWorlds; ++w) builder.add_motor(w, 2);
          SolverFeatherstoneSettings settings;
          settings.on_divergence = policy;
          settings.use_batch_kernels = batched;
          Scene scene(builder, settings);
          State& state = scene.state;
          Control& control = scene.control;
          std::fill(control.actuator_ctrl.begin(), control.actuator_ctrl.end(), 0.5);
          poison.set(state, control);
          const State before = state;
          const std::string where = std::string(poison.message) + (batched ? ", blocks" : ", dense") + ", policy " +
                                    std::to_string(static_cast<int>(policy)) + ", precision " +
                                    std::to_string(static_cast<int>(precision));
          SCOPED_TRACE(where);
          EXPECT_NOVAPHY_ERROR(scene.solver.step(state, state, control, scene.contacts, kDt), poison.message);
          EXPECT_TRUE(same_bits(state.joint_q[kBad], before.joint_q[kBad]));
          EXPECT_TRUE(same_bits(state.joint_qd[kBad], before.joint_qd[kBad]));
          for (int m = 0; m < 7; ++m) EXPECT_EQ(state.body_q[7 * kBad + m], before.body_q[7 * kBad + m]);
          for (const int w : {0, kBad + 1})
            if (policy == DivergencePolicy::Raise)
              EXPECT_EQ(state.joint_qd[w], before.joint_qd[w]) << "world " << w;
            else
              EXPECT_NE(state.joint_qd[w], before.joint_qd[w]) << "world " << w;
          state.joint_q[kBad] = scene.model.joint_q0[kBad];  // the next step goes on from there, its input mended
          state.joint_qd[kBad] = 0;
          state.body_f = scene.model.state().body_f;
          control = scene.model.control();
          scene.solver.step(state, state, control, scene.contacts, kDt);
          EXPECT_NE(state.joint_qd[kBad], 0);
          EXPECT_TRUE(std::isfinite(state.joint_qd[kBad]));
        }
}

// a contact no collision pipeline makes: between the boxes of two worlds, which never touch
TEST(SolverFeatherstoneErrors, AContactBetweenWorldsIsNamed) {
  ModelBuilder world, builder;
  add_box(world, Vec3(0, 0.5, 0));
  builder.replicate(world, 2);
  Scene scene(builder);
  Contacts& contacts = scene.contacts;
  ASSERT_GE(contacts.contact_capacity, 1);
  contacts.contact_count = 1;
  contacts.contact_shape_a[0] = 0;
  contacts.contact_shape_b[0] = 1;
  contacts.contact_body_a[0] = 0;
  contacts.contact_body_b[0] = 1;
  contacts.contact_normal[2] = 1;
  EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, contacts, kDt),
                       "contact 0 joins body 0 of world 0 and body 1 of world 1: worlds never touch");
}

// ---- one call at a time per object ----

TEST(ExclusiveCall, AnotherThreadsCallThrowsANestedOneNotAndTheFlagIsReleasedAlsoWhenTheCallThrows) {
  CallFlag flag;
  {
    const ExclusiveCall first(flag, "Thing.run");
    std::string refused;
    std::thread other([&] {
      try {
        const ExclusiveCall second(flag, "Thing.run");
      } catch (const Error& e) {
        refused = e.what();
      }
    });
    other.join();
    EXPECT_EQ(refused,
              "Thing.run called while another call of the same object runs on another thread (use one object per "
              "thread)");
    {
      const ExclusiveCall nested(flag, "Thing.run");  // the same thread: taken again
    }
    EXPECT_TRUE(flag.held());  // (neither the refused call nor the nested one released the first's flag)
  }
  EXPECT_FALSE(flag.held());
  auto throwing = [&] {
    const ExclusiveCall call(flag, "Thing.run");
    fail("inside");
  };
  EXPECT_NOVAPHY_ERROR(throwing(), "inside");
  EXPECT_FALSE(flag.held());
  std::thread after([&] { const ExclusiveCall call(flag, "Thing.run"); });  // free for any thread again
  after.join();
}

// two threads stepping one solver and colliding with one pipeline, each its own state and contacts: every call
// completes or throws the clear error (writing nothing), and each thread's state is bit for bit what a solver and
// pipeline of its own make from the calls that completed, in the same order
TEST(SolverFeatherstoneErrors, ConcurrentStepsOfOneSolverCompleteOrRaiseNeverCorrupt) {
  ModelBuilder robot, worlds;
  robot.add_ground_plane();
  add_box(robot, Vec3(0, 0.25, 0));
  worlds.replicate(robot, 256);
  const Model model = worlds.finalize();
  SolverFeatherstoneSettings settings;
  settings.num_threads = 1;
  CollisionOptions options;
  options.num_threads = 1;
  SolverFeatherstone solver(model, settings);
  CollisionPipeline pipeline(model, options);
  const Control control = model.control();
  struct Run {
    State state;
    Contacts contacts;
    std::string calls;  // 'c' a collide, 's' a step that completed, in order
    int refused = 0;
    std::vector<std::string> other_errors;
  };
  std::vector<Run> runs(2);
  for (Run& r : runs) {
    r.state = model.state();
    r.contacts = pipeline.contacts();
  }
  auto refused = [](const Error& e, const char* call) {
    return std::string(e.what()) ==
           std::string(call) +
               " called while another call of the same object runs on another thread (use one object "
               "per thread)";
  };
  auto hammer = [&](Run& r) {
    for (int k = 0; k < 80; ++k) {
      try {
        pipeline.collide(r.state, r.contacts);
        r.calls += 'c';
        solver.step(r.state, r.state, control, r.contacts, kDt);
        r.calls += 's';
      } catch (const Error& e) {
        if (refused(e, "CollisionPipeline.collide") || refused(e, "SolverFeatherstone.step"))
          ++r.refused;
        else
          r.other_errors.push_back(e.what());
      }
    }
  };
  std::thread first(hammer, std::ref(runs[0])), second(hammer, std::ref(runs[1]));
  first.join();
  second.join();
  for (const Run& r : runs) {
    EXPECT_TRUE(r.other_errors.empty()) << r.other_errors.front();
    EXPECT_EQ(std::count(r.calls.begin(), r.calls.end(), 's') + r.refused, 80);
    SolverFeatherstone own_solver(model, settings);
    CollisionPipeline own_pipeline(model, options);
    Contacts contacts = own_pipeline.contacts();
    State state = model.state();
    for (const char call : r.calls) {
      if (call == 'c') own_pipeline.collide(state, contacts);
      if (call == 's') own_solver.step(state, state, control, contacts, kDt);
    }
    EXPECT_EQ(r.state.joint_q, state.joint_q);
    EXPECT_EQ(r.state.joint_qd, state.joint_qd);
    EXPECT_EQ(r.state.body_q, state.body_q);
    EXPECT_EQ(r.contacts.contact_count, contacts.contact_count);
    EXPECT_EQ(r.contacts.contact_impulse, contacts.contact_impulse);
  }
}

// ---- non-finite and negative controls ----

// four worlds of a pendulum with a motor whose command is clamped to [-1, 1]: an infinite command raises naming
// the entry, its world and value, as NaN does, the other worlds stepped and that one left as it was
TEST(SolverFeatherstoneErrors, AnInfiniteCommandRaisesAsNanDoes) {
  ModelBuilder robot, worlds;
  const int link = robot.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)));
  JointOptions joint;
  joint.dof.axis = Vec3::UnitZ();
  joint.child_xform.p = Vec3(-0.25, 0, 0);
  robot.add_motor(robot.add_joint_revolute(-1, link, joint), 1, -1, 1);
  worlds.replicate(robot, 4);
  for (const bool batched : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = batched;
    Scene scene(worlds, settings), calm(worlds, settings);
    for (const Scalar bad :
         {std::numeric_limits<Scalar>::infinity(), -std::numeric_limits<Scalar>::infinity(), std::nan("")}) {
      scene.state = scene.model.state();
      scene.control.actuator_ctrl[2] = bad;
      std::ostringstream expected;
      expected << "actuator_ctrl[2] is not finite: " << bad << " (world 2)";
      EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                           expected.str());
      calm.state = calm.model.state();
      calm.solver.step(calm.state, calm.state, calm.control, calm.contacts, kDt);
      for (const int w : {0, 1, 3}) EXPECT_EQ(scene.state.joint_qd[w], calm.state.joint_qd[w]);
      EXPECT_EQ(scene.state.joint_q[2], scene.model.joint_q0[2]);  // left as it was
      EXPECT_EQ(scene.state.joint_qd[2], 0);
    }
  }
}

// a negative PD gain written into the control raises naming the entry, its world and value, as the builder refuses
// it; the other worlds step
TEST(SolverFeatherstoneErrors, ANegativeGainInTheControlRaises) {
  for (const bool batched : {true, false}) {
    SolverFeatherstoneSettings settings;
    settings.use_batch_kernels = batched;
    Scene scene(pendulum_worlds(Precision::Float64), settings);
    scene.control.joint_target_ke[1] = -5;
    EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                         "joint_target_ke[1] must be >= 0 (as the builder's gains), got -5 (world 1)");
    EXPECT_NE(scene.state.joint_q[0], scene.model.joint_q0[0]);  // the others stepped
    EXPECT_EQ(scene.state.joint_q[1], scene.model.joint_q0[1]);
    scene.control.joint_target_ke[1] = 0;
    scene.control.joint_target_kd[3] = -0.5;
    settings.on_divergence = DivergencePolicy::Raise;
    scene.solver.settings = settings;
    const State before = scene.state;
    EXPECT_NOVAPHY_ERROR(scene.solver.step(scene.state, scene.state, scene.control, scene.contacts, kDt),
                         "joint_target_kd[3] must be >= 0 (as the builder's gains), got -0.5 (world 3)");
    EXPECT_EQ(scene.state.joint_q, before.joint_q);  // under Raise nothing is written
  }
}

}  // namespace
}  // namespace novaphy
