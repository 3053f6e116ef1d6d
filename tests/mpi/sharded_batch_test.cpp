// ShardedBatch under mpirun -np 2 (ctest runs it so): sharded worlds step bit-identically to the
// same worlds in one process, per-world arrays travel between ranks, and an error on one rank is
// raised on every rank without a hang.
#include "engine/mpi/sharded_batch.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>

#include "test_support_errors.h"
#include "tools/robot_grid.h"

namespace novaphy {
namespace {

// world w: a quadruped of the grid (bench/scenes/quadruped.xml) 0.3 m above the shared ground
WorldBuilder quadrupeds() { return robot_grid(NOVAPHY_SCENE_DIR "/quadruped.xml", 3, 0.3); }

// deterministic actions for every world and dof
std::vector<Scalar> actions(int world_count, int dofs, int step) {
  std::vector<Scalar> f(world_count * dofs);
  for (size_t i = 0; i < f.size(); ++i) f[i] = 3 * std::sin(0.01 * step + 0.7 * i);
  return f;
}

TEST(ShardedBatch, StepsEveryWorldBitIdenticallyToOneProcess) {
  const int worlds = 5, steps = 150;  // 3 + 2 worlds on two ranks
  const Scalar dt = 0.005;
  ShardedBatch batch(MPI_COMM_WORLD, worlds, grid_ground(), quadrupeds());
  ASSERT_EQ(batch.size(), 2) << "run under mpirun -np 2";
  EXPECT_EQ(batch.range().count(), batch.rank() == 0 ? 3 : 2);
  const int nq = batch.layout().joint_coord_count, nv = batch.layout().joint_dof_count;

  // the reference: all worlds in this process, the same model as build_worlds makes on one rank
  const Model all = build_worlds(grid_ground(), quadrupeds(), {0, worlds});
  CollisionPipeline pipeline(all);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstone solver(all);
  State state = all.state();
  Control control = all.control();

  std::vector<Scalar> q(worlds * nq), qd(worlds * nv);
  for (int s = 0; s < steps; ++s) {
    const std::vector<Scalar> f = actions(worlds, nv, s);
    batch.scatter<Scalar>(f, batch.control().joint_f);
    control.joint_f = f;
    batch.step(dt);
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, dt);
  }
  batch.all_gather<Scalar>(batch.state().joint_q, q);
  batch.all_gather<Scalar>(batch.state().joint_qd, qd);
  for (int k = 0; k < worlds * nq; ++k) ASSERT_EQ(q[k], state.joint_q[k]) << "coordinate " << k;
  for (int k = 0; k < worlds * nv; ++k) ASSERT_EQ(qd[k], state.joint_qd[k]) << "dof " << k;
  EXPECT_GT(std::abs(q[2] - 0.75), 0.1) << "the robots moved";
}

TEST(ShardedBatch, GatherAndScatterPlaceEachWorldsValuesInWorldOrder) {
  const int worlds = 7;
  ShardedBatch batch(MPI_COMM_WORLD, worlds, grid_ground(), quadrupeds());
  const WorldRange range = batch.range();
  std::vector<int> local(2 * range.count());
  for (int w = range.begin; w < range.end; ++w) {
    local[2 * (w - range.begin)] = 10 * w;
    local[2 * (w - range.begin) + 1] = -w;
  }
  std::vector<int> global(batch.rank() == 1 ? 2 * worlds : 0);
  batch.gather<int>(local, global, 1);
  for (int w = 0; w < (batch.rank() == 1 ? worlds : 0); ++w) {
    EXPECT_EQ(global[2 * w], 10 * w);
    EXPECT_EQ(global[2 * w + 1], -w);
  }

  std::vector<double> everything(batch.rank() == 0 ? 3 * worlds : 0), mine(3 * range.count());
  for (size_t i = 0; i < everything.size(); ++i) everything[i] = 0.5 * i;
  batch.scatter<double>(everything, mine);
  for (size_t i = 0; i < mine.size(); ++i) EXPECT_EQ(mine[i], 0.5 * (3 * range.begin + i));

  std::vector<int> wrong(3 * worlds);
  EXPECT_NOVAPHY_ERROR(batch.gather<int>(local, wrong), "gather: the global array holds 21 values, 7 worlds need 14");
  std::vector<int> ragged(batch.rank() == 0 ? 2 * range.count() : 3 * range.count()), sink(2 * worlds);
  EXPECT_NOVAPHY_ERROR(batch.all_gather<int>(ragged, sink),
                       "all_gather: values per world differ between ranks (2 to 3)");
  EXPECT_NOVAPHY_ERROR(batch.gather<int>(local, global, 2), "gather: root must be in [0, 2), got 2");
}

TEST(ShardedBatch, AnErrorOnOneRankIsRaisedOnEveryRankAndNoStateChanges) {
  ShardedBatch batch(MPI_COMM_WORLD, 4, grid_ground(), quadrupeds());
  const State before = batch.state();
  if (batch.rank() == 1) batch.control().joint_f[20] = NAN;  // world 3's third dof
  EXPECT_NOVAPHY_ERROR(batch.step(0.005), "rank 1: joint_f[20] is not finite");
  EXPECT_EQ(batch.state().joint_q, before.joint_q);
  batch.control().joint_f[20] = 0;
  EXPECT_NOVAPHY_ERROR(batch.step(-1), "rank 0: dt must be finite and > 0, got -1");
  EXPECT_NOVAPHY_ERROR(ShardedBatch(MPI_COMM_WORLD, 1, grid_ground(), quadrupeds()),
                       "rank 0: ShardedBatch: world_count must be at least the number of ranks (2), got 1");
  const WorldBuilder uneven = [](ModelBuilder& builder, int w) {
    for (int k = 0; k <= w / 2; ++k) builder.add_body(RigidBody::from_sphere(1, 0.1));  // rank 1 builds more
  };
  EXPECT_NOVAPHY_ERROR(ShardedBatch(MPI_COMM_WORLD, 4, grid_ground(), uneven),
                       "ShardedBatch: worlds differ between ranks: 1 to 2 bodies per world");
}

TEST(ShardedBatch, DivergedWorldsAreFlaggedAndGatheredWithoutDisturbingTheOthers) {
  ShardedBatch batch(MPI_COMM_WORLD, 6, grid_ground(), quadrupeds());
  const int nq = batch.layout().joint_coord_count, nv = batch.layout().joint_dof_count;
  if (batch.rank() == 1) batch.state().joint_qd[nv + 8] = 1e7;  // world 4, beyond divergence_speed
  const State before = batch.state();
  batch.step(0.005);
  std::vector<std::uint8_t> flags(batch.rank() == 0 ? 6 : 0);
  batch.gather<std::uint8_t>(batch.diverged(), flags);
  if (batch.rank() == 0) {
    EXPECT_EQ(flags, (std::vector<std::uint8_t>{0, 0, 0, 0, 1, 0}));
  }
  // Flag keeps the diverged world where it was; every other world fell under gravity
  for (int w = 0; w < batch.range().count(); ++w) {
    const bool flagged = batch.range().begin + w == 4;
    EXPECT_EQ(batch.state().joint_q[w * nq + 2] == before.joint_q[w * nq + 2], flagged) << "world " << w;
  }
}

}  // namespace
}  // namespace novaphy

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0)
    delete ::testing::UnitTest::GetInstance()->listeners().Release(
        ::testing::UnitTest::GetInstance()->listeners().default_result_printer());
  const int mine = RUN_ALL_TESTS();
  int worst = 0;
  MPI_Allreduce(&mine, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (mine != 0) std::fprintf(stderr, "rank %d: tests failed\n", rank);
  MPI_Finalize();
  return worst;
}
