#include "kernels/cholesky.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

namespace novaphy {
namespace {

TEST(Cholesky, FactorAndSolveMatchEigen) {
  for (const int n : {1, 2, 7, 30}) {
    const MatX A = MatX::Random(n, n);
    const MatX H = A * A.transpose() + MatX::Identity(n, n);
    const VecX b = VecX::Random(n);

    MatX L = H;
    ASSERT_EQ(cholesky_factor(L), -1);
    VecX x = b;
    cholesky_solve(L, x.data());

    const VecX expected = H.llt().solve(b);
    EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff()) << "n = " << n;
    const MatX lower = L.triangularView<Eigen::Lower>();
    EXPECT_LT((lower * lower.transpose() - H).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
  }
}

// the fused kernel does the same arithmetic in another order of passes: identical bits
TEST(Cholesky, FusedFactorSolveEqualsFactorThenSolve) {
  const MatX A = MatX::Random(12, 12);
  const MatX H = A * A.transpose() + MatX::Identity(12, 12);
  const VecX b = VecX::Random(12);
  MatX L_split = H, L_fused = H;
  VecX x_split = b, x_fused = b;
  ASSERT_EQ(cholesky_factor(L_split), -1);
  cholesky_solve(L_split, x_split.data());
  ASSERT_EQ(cholesky_factor_solve(L_fused, x_fused.data()), -1);
  EXPECT_EQ(x_fused, x_split);
  EXPECT_EQ(MatX(L_fused.triangularView<Eigen::Lower>()), MatX(L_split.triangularView<Eigen::Lower>()));
  MatX bad = -MatX::Identity(3, 3);
  VecX y = VecX::Ones(3);
  EXPECT_EQ(cholesky_factor_solve(bad, y.data()), 0);
}

TEST(Cholesky, ReportsTheFirstPivotThatIsNotPositive) {
  MatX H = MatX::Identity(4, 4);
  H(2, 2) = 0;
  EXPECT_EQ(cholesky_factor(H), 2);

  MatX indefinite(2, 2);
  indefinite << 1, 2, 2, 1;
  EXPECT_EQ(cholesky_factor(indefinite), 1);

  MatX nan = MatX::Identity(3, 3);
  nan(0, 0) = std::nan("");
  EXPECT_EQ(cholesky_factor(nan), 0);
}

}  // namespace
}  // namespace novaphy
