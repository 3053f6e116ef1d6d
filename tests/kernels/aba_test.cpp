#include "kernels/aba.h"

#include <gtest/gtest.h>

#include "engine/dynamics.h"
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

}  // namespace
}  // namespace novaphy
