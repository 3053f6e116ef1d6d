#include "engine/mpi/shard.h"

#include <gtest/gtest.h>

#include "test_support_errors.h"

namespace novaphy {
namespace {

TEST(ShardRange, CoversEveryWorldOnceInRankOrderWithinOneOfEachOther) {
  for (int worlds : {0, 1, 5, 7, 100, 4096})
    for (int size : {1, 2, 3, 8}) {
      int next = 0, smallest = worlds, largest = 0;
      for (int rank = 0; rank < size; ++rank) {
        const WorldRange range = shard_range(worlds, rank, size);
        EXPECT_EQ(range.begin, next) << worlds << " worlds, rank " << rank << " of " << size;
        EXPECT_GE(range.count(), 0);
        smallest = std::min(smallest, range.count());
        largest = std::max(largest, range.count());
        next = range.end;
      }
      EXPECT_EQ(next, worlds);
      EXPECT_LE(largest - smallest, 1);
    }
  EXPECT_NOVAPHY_ERROR(shard_range(10, 2, 2), "shard_range: rank must be in [0, 2), got 2");
  EXPECT_NOVAPHY_ERROR(shard_range(10, 0, 0), "shard_range: size must be >= 1, got 0");
  EXPECT_NOVAPHY_ERROR(shard_range(-1, 0, 1), "shard_range: world_count must be >= 0, got -1");
}

// world w: a pendulum whose anchor sits at x = w, with w % 3 + 1 links when `uneven`
WorldBuilder pendulums(bool uneven) {
  return [uneven](ModelBuilder& builder, int w) {
    int parent = -1;
    for (int k = 0; k < (uneven ? w % 3 + 1 : 2); ++k) {
      const int body = builder.add_body(RigidBody::from_sphere(1, 0.1));
      JointOptions options;
      options.parent_xform.p = parent < 0 ? Vec3(w, 0, 0) : Vec3(0, -0.5, 0);
      builder.add_joint_revolute(parent, body, options);
      parent = body;
    }
  };
}

TEST(BuildWorlds, ARangeOfWorldsIsTheSameSliceOfAllWorlds) {
  ModelBuilder shared;
  shared.add_ground_plane(-2);
  const Model all = build_worlds(shared, pendulums(false), {0, 6});
  const Model part = build_worlds(shared, pendulums(false), {4, 6});
  EXPECT_EQ(all.world_count, 6);
  EXPECT_EQ(part.world_count, 2);
  EXPECT_EQ(part.shape_count, 1);  // the shared plane, once
  EXPECT_EQ(part.shape_world[0], -1);
  const WorldLayout layout = world_layout(all);
  EXPECT_EQ(layout.body_count, 2);
  EXPECT_EQ(layout.joint_dof_count, 2);
  EXPECT_EQ(layout.articulation_count, 1);
  const int offset = 4 * layout.joint_dof_count;
  for (int k = 0; k < part.joint_count; ++k)
    for (int c = 0; c < 7; ++c)
      EXPECT_EQ(part.joint_X_p[7 * k + c], all.joint_X_p[7 * (offset + k) + c]) << "joint " << k;
}

TEST(BuildWorlds, SharedBodiesAndUnevenWorldsAreErrors) {
  ModelBuilder shared;
  shared.add_body(RigidBody::from_sphere(1, 0.1));
  EXPECT_NOVAPHY_ERROR(build_worlds(shared, pendulums(false), {0, 2}),
                       "build_worlds: the shared builder holds 1 bodies; it may hold only static shapes");
  EXPECT_NOVAPHY_ERROR(build_worlds(ModelBuilder(), pendulums(false), {3, 2}), "invalid world range [3, 2)");
  const Model uneven = build_worlds(ModelBuilder(), pendulums(true), {0, 3});
  EXPECT_NOVAPHY_ERROR(world_layout(uneven), "world_layout: world 1 has 2 bodies, world 0 has 1");
}

}  // namespace
}  // namespace novaphy
