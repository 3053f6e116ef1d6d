// SolverSemiImplicit and SolverXPBD against independent oracles: SolverFeatherstone on the same scene (a pendulum, a
// D6 set up as a hinge, boxes at rest), analytic solutions (a Distance joint's spring period, a cable's catenary), and
// their own runs (one thread against two, a world alone against replicated worlds); the divergence guard and bad
// input.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/builder.h"
#include "engine/solver/semi_implicit/solver_semi_implicit.h"
#include "engine/solver/solver_featherstone.h"
#include "engine/solver/xpbd/solver_xpbd.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

constexpr Scalar kPi = 3.14159265358979323846;

// a model, its pipeline and contacts, a state and control, stepped by any solver
struct Scene {
  explicit Scene(Model m) : model(std::move(m)), pipeline(model), contacts(pipeline.contacts()) {
    state = model.state();
    control = model.control();
  }
  template <typename Solver>
  void steps(Solver& solver, int count, Scalar dt, const std::function<void()>& after = {}) {
    for (int k = 0; k < count; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, control, contacts, dt);
      if (after) after();
    }
  }
  Vec3 position(int b) const { return Eigen::Map<const Vec3>(&state.body_q[7 * static_cast<size_t>(b)]); }
  Model model;
  CollisionPipeline pipeline;
  Contacts contacts;
  State state;
  Control control;
};

SolverSemiImplicitSettings semi_implicit_settings() {
  SolverSemiImplicitSettings s;
  s.angular_damping = 0;
  return s;
}

// a rod of 0.5 m swinging about the world's z axis from its top end, 1 rad from hanging; `hinge` adds the joint
ModelBuilder rod(const std::function<void(ModelBuilder&, int, const JointOptions&)>& hinge) {
  ModelBuilder b;
  const Transform hanging{Vec3(0.25 * std::sin(1.0), -0.25 * std::cos(1.0), 0),
                          Quat(Eigen::AngleAxisd(1.0, Vec3::UnitZ()))};
  const int body = b.add_body(RigidBody::from_box(1, Vec3(0.05, 0.25, 0.05)), hanging);
  JointOptions options;
  options.child_xform.p = Vec3(0, 0.25, 0);
  hinge(b, body, options);
  return b;
}
ModelBuilder revolute_rod() {
  return rod([](ModelBuilder& b, int body, JointOptions options) {
    options.dof.axis = Vec3::UnitZ();
    options.dof.q0 = 1.0;
    b.add_joint_revolute(-1, body, options);
  });
}
ModelBuilder d6_hinge_rod() {
  return rod([](ModelBuilder& b, int body, const JointOptions& options) {
    JointDofConfig z;
    z.axis = Vec3::UnitZ();
    b.add_joint_d6(-1, body, options, {}, {z});
  });
}

// the rod's angle from hanging, from its pose
Scalar rod_angle(const State& state) {
  const Quat q(state.body_q[6], state.body_q[3], state.body_q[4], state.body_q[5]);
  const Vec3 down = q * Vec3(0, -1, 0);
  return std::atan2(down.x(), -down.y());
}

TEST(MaximalSolvers, PendulumSwingsAsFeatherstones) {
  const Model model = revolute_rod().finalize();
  SolverFeatherstoneSettings fs;
  fs.angular_damping = 0;
  SolverFeatherstone reference(model, fs);
  SolverSemiImplicit semi(model, semi_implicit_settings());
  SolverXPBD xpbd(model);
  Scene a(model), b(model), c(model);
  for (int k = 0; k < 5; ++k) {
    a.steps(reference, 100, 0.002);
    b.steps(semi, 100, 0.002);
    c.steps(xpbd, 100, 0.002);
    EXPECT_NEAR(b.state.joint_q[0], a.state.joint_q[0], 2e-3) << "after " << 100 * (k + 1) << " steps";
    EXPECT_NEAR(c.state.joint_q[0], a.state.joint_q[0], 1e-2) << "after " << 100 * (k + 1) << " steps";
    EXPECT_NEAR(b.state.joint_qd[0], a.state.joint_qd[0], 2e-2);
    EXPECT_NEAR(rod_angle(b.state), b.state.joint_q[0], 1e-9);  // joint_q follows the bodies
  }
  // the pivot stays where the joint holds it
  const Quat q(b.state.body_q[6], b.state.body_q[3], b.state.body_q[4], b.state.body_q[5]);
  EXPECT_LT((b.position(0) + q * Vec3(0, 0.25, 0)).norm(), 1e-4);
}

// a D6 whose one free axis is angular z moves as Featherstone's Revolute: XPBD's trajectory converges to the
// converged one (Featherstone at dt 1e-5) as its substeps rise, at first order in h; SolverSemiImplicit's is as close
// as Featherstone's own at the same dt
TEST(MaximalSolvers, D6HingeConvergesToFeatherstonesRevolute) {
  const Model hinge = d6_hinge_rod().finalize(), revolute = revolute_rod().finalize();
  EXPECT_EQ(static_cast<JointType>(hinge.joint_type[0]), JointType::D6);
  SolverFeatherstoneSettings fs;
  fs.angular_damping = 0;
  SolverFeatherstone reference(revolute, fs);
  Scene exact(revolute);
  exact.steps(reference, 50000, 1e-5);
  std::vector<Scalar> error;
  for (int substeps : {1, 4, 16}) {
    SolverXPBDSettings s;
    s.substeps = substeps;
    SolverXPBD xpbd(hinge, s);
    Scene run(hinge);
    run.steps(xpbd, 250, 0.002);
    error.push_back(std::abs(rod_angle(run.state) - rod_angle(exact.state)));
  }
  EXPECT_LT(error[1], error[0] / 3);
  EXPECT_LT(error[2], error[1] / 3);
  EXPECT_LT(error[2], 2e-3);
  SolverSemiImplicit semi(hinge, semi_implicit_settings());
  Scene run(hinge);
  run.steps(semi, 250, 0.002);
  EXPECT_NEAR(rod_angle(run.state), rod_angle(exact.state), 4e-3);
}

// a ball on a Distance joint of min = max = L and compliance alpha, stretched: a spring of stiffness 1 / alpha,
// period 2 pi sqrt(m alpha)
TEST(MaximalSolvers, DistanceJointOfComplianceIsASpring) {
  constexpr Scalar mass = 2, alpha = 1e-3, length = 1;
  ModelBuilder b(Vec3::Zero());
  const int ball =
      b.add_body(RigidBody::from_sphere(mass, 0.05), Transform{Vec3(0, -length - 0.05, 0), Quat::Identity()});
  b.add_joint_distance(-1, ball, {}, length, length, alpha);
  const Model model = b.finalize();
  const Scalar period = 2 * kPi * std::sqrt(mass * alpha);
  auto measured = [&](auto& solver, Scalar dt) {
    Scene run(model);
    std::vector<Scalar> up;  // the times the stretch crosses zero upwards
    Scalar last = run.position(0).y() + length;
    int k = 0;
    run.steps(solver, static_cast<int>(2.5 * period / dt), dt, [&] {
      ++k;
      const Scalar x = run.position(0).y() + length;
      if (last < 0 && x >= 0) up.push_back((k - 1 + (-last / (x - last))) * dt);
      last = x;
    });
    EXPECT_GE(up.size(), 2u);
    return up.size() >= 2 ? up[1] - up[0] : 0;
  };
  SolverSemiImplicit semi(model, semi_implicit_settings());
  SolverXPBD xpbd(model);
  EXPECT_NEAR(measured(semi, 1e-4), period, 0.01 * period);
  EXPECT_NEAR(measured(xpbd, 1e-3), period, 0.01 * period);
}

// three boxes stacked on the ground rest where SolverFeatherstone rests them
TEST(MaximalSolvers, FreeBodiesRestWhereFeatherstoneRests) {
  ModelBuilder b;
  b.add_ground_plane();
  for (int i = 0; i < 3; ++i) {
    const int box = b.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)),
                               Transform{Vec3(0, 0.1 + 0.21 * i, 0), Quat::Identity()});
    b.add_shape_box(box, Vec3(0.1, 0.1, 0.1));
  }
  const Model model = b.finalize();
  SolverFeatherstone reference(model);
  SolverSemiImplicit semi(model);
  SolverXPBD xpbd(model);
  Scene a(model), s(model), x(model);
  a.steps(reference, 960, 1.0 / 240);
  s.steps(semi, 960, 1.0 / 240);
  x.steps(xpbd, 960, 1.0 / 240);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT((s.position(i) - a.position(i)).norm(), 3e-3) << "box " << i;
    EXPECT_LT((x.position(i) - a.position(i)).norm(), 3e-3) << "box " << i;
  }
  for (const State* st : {&s.state, &x.state})
    for (Scalar v : st->body_qd) EXPECT_LT(std::abs(v), 1e-2);
}

// a rope of segments joined by Cable joints (stiff to stretch, soft to bend), hung between two points: its sag is
// the catenary's of its length
TEST(MaximalSolvers, CableSagsAsTheCatenary) {
  constexpr int n = 20;
  constexpr Scalar span = 1.6, length = 2.0, segment = length / n;
  // laid as a V between (0, 0) and (span, 0), the halves' slope from their length
  const Scalar drop = std::sqrt(0.25 * length * length - 0.25 * span * span);
  ModelBuilder b;
  int parent = -1;
  Vec3 start(0, 0, 0);
  for (int i = 0; i < n; ++i) {
    const Vec3 dir = (i < n / 2 ? Vec3(0.5 * span, -drop, 0) : Vec3(0.5 * span, drop, 0)).normalized();
    const Quat turn = Quat::FromTwoVectors(Vec3::UnitY(), -dir);  // the segment's -y along the rope
    const int body =
        b.add_body(RigidBody::from_capsule(0.1, 0.01, 0.5 * segment), Transform{start + 0.5 * segment * dir, turn});
    JointOptions options;
    options.child_xform.p = Vec3(0, 0.5 * segment, 0);
    options.parent_xform.p = parent >= 0 ? Vec3(0, -0.5 * segment, 0) : start;
    b.add_joint_cable(parent, body, options, 0, 10);
    parent = body;
    start += segment * dir;
  }
  b.add_connect(parent, -1, Vec3(0, -0.5 * segment, 0));
  const Model model = b.finalize();
  // the catenary y = a cosh(x / a) through both ends: length = 2 a sinh(span / 2a)
  Scalar a = 1;
  for (int it = 0; it < 100; ++it) {  // (Newton's method on f(a) = 2 a sinh(span / 2a) - length)
    const Scalar u = span / (2 * a);
    const Scalar f = 2 * a * std::sinh(u) - length, df = 2 * std::sinh(u) - 2 * u * std::cosh(u);
    a -= f / df;
  }
  const Scalar sag = a * (std::cosh(span / (2 * a)) - 1);
  SolverXPBDSettings settings;
  settings.angular_damping = 10;  // (the sway settles)
  SolverXPBD xpbd(model, settings);
  Scene run(model);
  run.steps(xpbd, 2400, 1.0 / 120);
  // the lowest joint: the end of segment n / 2 - 1
  const Quat q(run.state.body_q[7 * (n / 2) + 6], run.state.body_q[7 * (n / 2) + 3], run.state.body_q[7 * (n / 2) + 4],
               run.state.body_q[7 * (n / 2) + 5]);
  const Vec3 low = run.position(n / 2) + q * Vec3(0, 0.5 * segment, 0);
  EXPECT_NEAR(-low.y(), sag, 0.02 * sag);
  EXPECT_NEAR(low.x(), 0.5 * span, 0.01 * span);
}

template <typename Solver, typename Settings>
void expect_same_bits_on_any_thread_count(const Model& model) {
  std::vector<std::vector<Scalar>> runs;
  for (int threads : {1, 2}) {
    Settings s;
    s.num_threads = threads;
    Solver solver(model, s);
    Scene run(model);
    run.steps(solver, 200, 1.0 / 240);
    runs.push_back(run.state.body_q);
    runs.back().insert(runs.back().end(), run.state.joint_q.begin(), run.state.joint_q.end());
  }
  EXPECT_EQ(runs[0], runs[1]);
}

// worlds of a box on a hinge and a falling box, replicated: the same bits on one thread and two, and each world
// as the same world alone
ModelBuilder hinge_and_box() {
  ModelBuilder b = revolute_rod();
  b.add_ground_plane(-0.6);
  const int box = b.add_body(RigidBody::from_box(1, Vec3(0.1, 0.1, 0.1)), Transform{Vec3(1, 0.2, 0), Quat::Identity()});
  b.add_shape_box(box, Vec3(0.1, 0.1, 0.1));
  return b;
}

TEST(MaximalSolvers, SameBitsOnAnyThreadCountAndAsAWorldAlone) {
  ModelBuilder worlds;
  worlds.replicate(hinge_and_box(), 5, Vec3(3, 0, 0));
  const Model model = worlds.finalize();
  expect_same_bits_on_any_thread_count<SolverSemiImplicit, SolverSemiImplicitSettings>(model);
  expect_same_bits_on_any_thread_count<SolverXPBD, SolverXPBDSettings>(model);
  // world 3 (placed 9 m along x) as the scene alone
  const Model alone = hinge_and_box().finalize();
  SolverXPBD many(model), one(alone);
  Scene m(model), o(alone);
  m.steps(many, 100, 1.0 / 240);
  o.steps(one, 100, 1.0 / 240);
  for (int body = 0; body < 2; ++body)
    for (int k = 0; k < 7; ++k)
      EXPECT_NEAR(m.state.body_q[7 * (6 + body) + k] - (k == 0 ? 9 : 0), o.state.body_q[7 * body + k], 1e-9);
}

TEST(MaximalSolvers, Float32StatesRoundEachStep) {
  ModelBuilder b = hinge_and_box();
  b.set_precision(Precision::Float32);
  const Model model = b.finalize();
  SolverSemiImplicit solver(model);
  Scene run(model);
  run.steps(solver, 50, 1.0 / 240);
  for (Scalar x : run.state.body_q) EXPECT_EQ(x, static_cast<Scalar>(static_cast<float>(x)));
  for (Scalar x : run.state.joint_qd) EXPECT_EQ(x, static_cast<Scalar>(static_cast<float>(x)));
}

TEST(MaximalSolvers, DivergedWorldsAreFlaggedOrReset) {
  ModelBuilder worlds;
  worlds.replicate(hinge_and_box(), 2);
  const Model model = worlds.finalize();
  SolverSemiImplicitSettings s;
  s.divergence_speed = 50;
  Scene run(model);
  run.state.body_qd[6 * 3 + 1] = 1e3;  // world 1's box thrown faster than that
  const State before = run.state;
  SolverSemiImplicit flag(model, s);
  run.steps(flag, 1, 1.0 / 240);
  EXPECT_EQ(flag.diverged(), (std::vector<std::uint8_t>{0, 1}));
  EXPECT_EQ(run.state.body_q[7 * 3 + 1], before.body_q[7 * 3 + 1]);  // kept as it was
  EXPECT_NE(run.state.body_q[1], before.body_q[1]);                  // world 0 stepped
  s.on_divergence = DivergencePolicy::Reset;
  SolverSemiImplicit reset(model, s);
  run.steps(reset, 1, 1.0 / 240);
  EXPECT_EQ(run.state.world_reset[1], 1);
  EXPECT_EQ(run.state.body_qd[6 * 3 + 1], 0);
  run.state.body_qd[6 * 3 + 1] = 1e3;
  const State held = run.state;
  SolverXPBDSettings x;
  x.divergence_speed = 50;
  x.on_divergence = DivergencePolicy::Raise;
  SolverXPBD raise(model, x);
  EXPECT_NOVAPHY_ERROR(run.steps(raise, 1, 1.0 / 240), "SolverXPBD: world 1 diverged");
  EXPECT_EQ(run.state.body_q, held.body_q);
}

TEST(MaximalSolvers, JointSupportAndFeatherstonesRefusal) {
  const Model model = d6_hinge_rod().finalize();
  for (const JointSupportMatrix& support :
       {SolverSemiImplicit(model).joint_support(), SolverXPBD(model).joint_support()})
    for (const char* joint : {"Revolute", "Prismatic", "Slide", "Ball", "Fixed", "Free", "Distance", "D6", "Cable"})
      EXPECT_TRUE(support.supports(joint)) << joint;
  EXPECT_NOVAPHY_ERROR(SolverFeatherstone{model},
                       "SolverFeatherstone does not enforce joint 0 (D6), a maximal-coordinate joint: use "
                       "SolverSemiImplicit or SolverXPBD");
}

TEST(MaximalSolvers, BadSettingsAndInputsAreNamed) {
  const Model model = revolute_rod().finalize();
  SolverXPBDSettings x;
  x.iterations = 0;
  EXPECT_NOVAPHY_ERROR(SolverXPBD(model, x), "settings.iterations must be >= 1, got 0");
  x = {};
  x.joint_linear_compliance = -1;
  EXPECT_NOVAPHY_ERROR(SolverXPBD(model, x), "settings.joint_linear_compliance must be >= 0");
  SolverSemiImplicitSettings s;
  s.num_iterations = -1;
  EXPECT_NOVAPHY_ERROR(SolverSemiImplicit(model, s), "settings.num_iterations must be >= 0, got -1");
  SolverSemiImplicit solver(model);
  Scene run(model);
  run.state.body_f[0] = std::nan("");
  EXPECT_NOVAPHY_ERROR(run.steps(solver, 1, 0.01), "state_in.body_f");
  run.state.body_f[0] = 0;
  EXPECT_NOVAPHY_ERROR(solver.step(run.state, run.state, run.control, run.contacts, 0), "dt must be finite and > 0");
  run.control.joint_target_ke[0] = -1;
  EXPECT_NOVAPHY_ERROR(run.steps(solver, 1, 0.01), "joint_target_ke and joint_target_kd must be >= 0");
}

TEST(MaximalSolvers, ModelsTheyDoNotModelAreRefused) {
  ModelBuilder b = revolute_rod();
  b.add_tendon({0}, {1.0});
  const Model model = b.finalize();
  EXPECT_NOVAPHY_ERROR(SolverXPBD{model}, "SolverXPBD does not model tendons");
}

// SolverSemiImplicit's position passes take out of the positions the drift its rows leave: a chain of hinged links
// whipping down from level opens its joints less with them
TEST(MaximalSolvers, PositionPassesHoldAWhippingChainCloser) {
  ModelBuilder b;
  int parent = -1;
  for (int i = 0; i < 8; ++i) {
    const int link = b.add_body(RigidBody::from_box(0.1, Vec3(0.1, 0.01, 0.01)),
                                Transform{Vec3(0.2 * i + 0.1, 0, 0), Quat::Identity()});
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.parent_xform.p = parent < 0 ? Vec3::Zero() : Vec3(0.1, 0, 0);
    options.child_xform.p = Vec3(-0.1, 0, 0);
    b.add_joint_revolute(parent, link, options);
    parent = link;
  }
  const Model model = b.finalize();
  std::vector<Scalar> worst;
  for (int passes : {0, 2}) {
    SolverSemiImplicitSettings s;
    s.position_iterations = passes;
    SolverSemiImplicit solver(model, s);
    Scene run(model);
    Scalar gap = 0;
    run.steps(solver, 240, 1.0 / 240, [&] {
      for (int i = 1; i < 8; ++i) {
        const Transform p = Transform::from_array(&run.state.body_q[7 * (i - 1)]);
        const Transform c = Transform::from_array(&run.state.body_q[7 * i]);
        gap = std::max(gap, (p.apply(Vec3(0.1, 0, 0)) - c.apply(Vec3(-0.1, 0, 0))).norm());
      }
    });
    worst.push_back(gap);
  }
  EXPECT_LT(worst[1], worst[0] / 2) << worst[0] << " " << worst[1];
}

}  // namespace
}  // namespace novaphy
