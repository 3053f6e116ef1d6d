#include "kernels/aba.h"

#include <gtest/gtest.h>

#include "engine/eval/eval.h"
#include "kernels/cholesky.h"
#include "kernels/fk.h"
#include "test_support.h"

namespace novaphy {
namespace {

// the O(n) articulated-body algorithm against CRBA + Cholesky on random trees
TEST(Aba, EqualsCrbaPlusCholesky) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 30; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 15, 1 + trial % 2);
    State state = model.state();
    test::randomize_state(model, state, rng, true);
    Control control = model.control();
    for (Scalar& f : control.joint_f) f = std::uniform_real_distribution<Scalar>(-5, 5)(rng);

    const VecX crba = eval_forward_dynamics(model, state, control, ForwardDynamicsMethod::Crba);
    const VecX aba = eval_forward_dynamics(model, state, control, ForwardDynamicsMethod::Aba);
    EXPECT_LT(test::relative_error(aba, crba), 1e-10) << "trial " << trial;
  }
}

// aba_factor + aba_solve (O(n)) against its reference twin, a dense Cholesky of H + diag
TEST(Aba, SolveEqualsCholeskyOfTheMassMatrixPlusADiagonal) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 12, 1);
    State state = model.state();
    test::randomize_state(model, state, rng, false);
    const ArticulationView art = model.articulation(0);
    const int nv = art.dof_count();
    if (nv == 0) continue;
    ArticulationScratch s;
    s.resize(art);
    forward_kinematics(art, state.joint_q.data() + art.q_begin(), s);
    VecX diagonal(nv), b(nv);
    for (int k = 0; k < nv; ++k) {
      diagonal[k] = std::uniform_real_distribution<Scalar>(0, 2)(rng);
      b[k] = std::uniform_real_distribution<Scalar>(-5, 5)(rng);
    }
    MatX M = eval_mass_matrix(model, state).block(art.qd_begin(), art.qd_begin(), nv, nv);
    M.diagonal() += diagonal;
    VecX expected = b;
    ASSERT_EQ(cholesky_factor(M), -1);
    cholesky_solve(M, expected.data());

    ASSERT_EQ(aba_factor(art, diagonal.data(), s), -1);
    VecX x = b;
    aba_solve(art, s, x.data());
    EXPECT_LT(test::relative_error(x, expected), 1e-10) << "trial " << trial << ", " << nv << " dofs";
    VecX again = 2 * b;  // the factor is reused: a second right-hand side
    aba_solve(art, s, again.data());
    EXPECT_LT(test::relative_error(again, 2 * expected), 1e-10) << "trial " << trial;
  }
}

}  // namespace
}  // namespace novaphy
