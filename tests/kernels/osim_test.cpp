#include "kernels/osim.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "engine/model/builder.h"
#include "kernels/fk.h"
#include "test_support.h"

namespace novaphy {
namespace {

// the O(n) recursion against its dense reference twin J_i H^-1 J_i^T on random trees at random poses: branching,
// every joint type (Ball, Fixed, and Free at a root), armature, fixed and floating bases (a link welded to the world
// has Omega = 0 in both)
TEST(OsimInverse, EqualsTheDenseReferenceOnRandomTrees) {
  std::mt19937 rng(5);
  int fixed_base = 0, floating = 0, branching = 0, balls = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const Model model = test::random_builder_tree(rng, 1 + trial % 16, 1);
    State state = model.state();
    test::randomize_state(model, state, rng, false);
    const ArticulationView art = model.articulation(0);
    if (art.dof_count() == 0) continue;
    ArticulationScratch s;
    s.resize(art);
    forward_kinematics(art, state.joint_q.data() + art.q_begin(), s);
    std::vector<Mat6> fast, ref;
    ASSERT_EQ(osim_inverse(art, s, fast), -1) << "trial " << trial;
    ASSERT_EQ(osim_inverse_ref(art, s, ref), -1) << "trial " << trial;
    ASSERT_EQ(fast.size(), static_cast<size_t>(art.link_count()));
    for (int i = 0; i < art.link_count(); ++i) {
      EXPECT_LE((fast[i] - ref[i]).cwiseAbs().maxCoeff(), 1e-10 * ref[i].cwiseAbs().maxCoeff())
          << "trial " << trial << " link " << i << "\n"
          << fast[i] << "\n\n"
          << ref[i];
      branching += i > 1 && art.parent(i) != i - 1;
      balls += art.type(i) == JointType::Ball;
    }
    (art.type(0) == JointType::Free ? floating : fixed_base) += 1;
  }
  EXPECT_GT(fixed_base, 5);
  EXPECT_GT(floating, 5);
  EXPECT_GT(branching, 5);
  EXPECT_GT(balls, 5);
}

// a free body alone: Omega is the inverse of its spatial inertia (a wrench on it meets nothing else), and
// armature on a Free joint's dofs makes it heavier
TEST(OsimInverse, OfAFreeBodyIsItsInverseSpatialInertia) {
  ModelBuilder builder;
  RigidBody body = RigidBody::from_box(2, Vec3(0.1, 0.2, 0.3));
  body.com = Vec3(0.05, -0.02, 0.1);
  builder.add_body(body);
  const Model model = builder.finalize();
  const ArticulationView art = model.articulation(0);
  ArticulationScratch s;
  s.resize(art);
  forward_kinematics(art, model.joint_q0.data(), s);
  std::vector<Mat6> Omega;
  ASSERT_EQ(osim_inverse(art, s, Omega), -1);
  const Mat6 expected = art.inertia(0).inverse();
  EXPECT_LT((Omega[0] - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
}

// a massless leaf (made so on the Model, as no builder call allows) is not positive definite: both report it, the
// recursion its link and the reference its dof (link and dof 1 here)
TEST(OsimInverse, ReportsAMassMatrixThatIsNotPositiveDefinite) {
  ModelBuilder builder;
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  const int base = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_revolute(-1, base, options);
  const int leaf = builder.add_body(RigidBody::from_sphere(1, 0.1));
  builder.add_joint_prismatic(base, leaf, options);
  Model model = builder.finalize();
  model.body_mass[leaf] = 0;
  std::fill_n(&model.body_inertia[9 * leaf], 9, Scalar(0));
  const ArticulationView art = model.articulation(0);
  ArticulationScratch s;
  s.resize(art);
  forward_kinematics(art, model.joint_q0.data(), s);
  std::vector<Mat6> Omega;
  EXPECT_EQ(osim_inverse(art, s, Omega), 1);
  EXPECT_EQ(osim_inverse_ref(art, s, Omega), 1);
}

}  // namespace
}  // namespace novaphy
