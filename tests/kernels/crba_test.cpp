#include "kernels/crba.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "engine/eval/eval.h"
#include "test_support.h"

namespace novaphy {
namespace {

// Pinocchio's oracle: column k of H is RNEA(q, qd, e_k) - RNEA(q, qd, 0)
TEST(Crba, MassMatrixEqualsRneaColumns) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::random_builder_tree(rng, 2 + trial % 9, 1 + trial % 3);
    State state = model.state();
    test::randomize_state(model, state, rng, true);

    const MatX H = eval_mass_matrix(model, state);
    const VecX bias = eval_bias_forces(model, state);
    MatX H_rnea(model.joint_dof_count, model.joint_dof_count);
    for (int k = 0; k < model.joint_dof_count; ++k)
      H_rnea.col(k) = eval_inverse_dynamics(model, state, VecX::Unit(model.joint_dof_count, k)) - bias;

    EXPECT_LT(test::relative_error(H, H_rnea), 1e-12) << "trial " << trial;
  }
}

TEST(Crba, MassMatrixIsSymmetricPositiveDefinite) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 12);
    State state = model.state();
    test::randomize_state(model, state, rng, false);
    const MatX H = eval_mass_matrix(model, state);
    if (H.rows() == 0) continue;
    EXPECT_EQ((H - H.transpose()).cwiseAbs().maxCoeff(), 0) << "trial " << trial;
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(H).eigenvalues().minCoeff(), 0) << "trial " << trial;
  }
}

}  // namespace
}  // namespace novaphy
