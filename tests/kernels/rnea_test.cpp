#include "kernels/rnea.h"

#include <gtest/gtest.h>

#include "engine/eval/eval.h"
#include "kernels/fk.h"
#include "test_support.h"

namespace novaphy {
namespace {

// inverse_dynamics(forward_dynamics(tau)) = tau
TEST(Rnea, InvertsForwardDynamics) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 30; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 10, 1 + trial % 3);
    State state = model.state();
    test::randomize_state(model, state, rng, true);
    Control control = model.control();
    for (Scalar& f : control.joint_f) f = std::uniform_real_distribution<Scalar>(-5, 5)(rng);
    const VecX tau = Eigen::Map<const VecX>(control.joint_f.data(), model.joint_dof_count);

    const VecX qdd = eval_forward_dynamics(model, state, control);
    EXPECT_LT(test::relative_error(eval_inverse_dynamics(model, state, qdd), tau), 1e-11) << "trial " << trial;
  }
}

// an applied wrench does virtual work through the body's velocity: qd . tau_ext = f . v_com + t . w
TEST(Rnea, AppliedWrenchesDoTheirVirtualWork) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 8);
    State state = model.state();
    test::randomize_state(model, state, rng, true);
    eval_fk(model, state);  // body_qd at this state
    const VecX with = eval_bias_forces(model, state);
    State unloaded = state;
    std::fill(unloaded.body_f.begin(), unloaded.body_f.end(), 0);
    const VecX tau_ext = eval_bias_forces(model, unloaded) - with;  // = J^T f

    Scalar power = 0;
    for (size_t k = 0; k < state.body_f.size(); ++k) power += state.body_f[k] * state.body_qd[k];
    const VecX qd = Eigen::Map<const VecX>(state.joint_qd.data(), model.joint_dof_count);
    EXPECT_NEAR(qd.dot(tau_ext), power, 1e-10 * std::max<Scalar>(1, std::abs(power))) << "trial " << trial;
  }
}

TEST(Rnea, PassiveForcesAreDampingAndSprings) {
  ModelBuilder builder(Vec3::Zero());
  const int body = builder.add_body(RigidBody::from_box(1, Vec3(0.1, 0.2, 0.3)));
  JointOptions options;
  options.dof.axis = Vec3(0, 0, 1);
  options.dof.damping = 0.7;
  options.dof.stiffness = 3;
  options.dof.q_ref = 0.25;
  builder.add_joint_revolute(-1, body, options);
  const Model model = builder.finalize();
  State state = model.state();
  state.joint_q[0] = 1.0;
  state.joint_qd[0] = 0;
  // at rest the only bias is the spring: bias = -tau_passive = k (q - q_ref)
  EXPECT_NEAR(eval_bias_forces(model, state)[0], 3 * 0.75, 1e-14);
  state.joint_qd[0] = 2.0;
  EXPECT_NEAR(eval_bias_forces(model, state)[0], 3 * 0.75 + 0.7 * 2.0, 1e-14);
}

// d bias / d qd against two independent facts: the velocity part of the bias is homogeneous of
// degree 2 in qd, so C qd = 2 (bias(qd) - bias(0)) (Euler); and a forward difference with a small
// step agrees to its own truncation error
TEST(Rnea, BiasVelocityJacobian) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 8, 1);
    State state = model.state();
    test::randomize_state(model, state, rng, true);
    const ArticulationView art = model.articulation(0);
    const int nv = art.dof_count();
    if (nv == 0) continue;
    ArticulationScratch s;
    s.resize(art);
    const Scalar* q = state.joint_q.data() + art.q_begin();
    const Scalar* qd = state.joint_qd.data() + art.qd_begin();
    auto bias = [&](const VecX& v) {
      VecX tau(nv);
      const VecX zero = VecX::Zero(nv);
      forward_velocity(art, v.data(), s);
      rnea(art, zero.data(), model.gravity, state.body_f.data(), s, tau.data());
      return tau;
    };
    forward_kinematics(art, q, s);
    MatX C;
    bias_velocity_jacobian(art, qd, s, C);
    const VecX v = Eigen::Map<const VecX>(qd, nv);
    EXPECT_LT(test::relative_error(C * v, 2 * (bias(v) - bias(VecX::Zero(nv)))), 1e-10) << "trial " << trial;
    const Scalar h = 1e-6;
    MatX forward(nv, nv);
    for (int k = 0; k < nv; ++k) forward.col(k) = (bias(v + h * VecX::Unit(nv, k)) - bias(v)) / h;
    EXPECT_LT(test::relative_error(C, forward), 1e-5) << "trial " << trial;
  }
}

}  // namespace
}  // namespace novaphy
