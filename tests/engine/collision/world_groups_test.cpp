// WorldGroups: worlds alike fall together into groups of up to kLanes; a world whose shapes differ in kind breaks a
// group, one whose shapes differ only in size or place joins it but is read apart; what each group's lanes read
// (bodies, runs, slots, planes) against the model's own arrays.
#include "engine/collision/world_groups.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "engine/collision/shape_filter.h"
#include "engine/collision/world_shapes.h"
#include "engine/model/builder.h"

namespace novaphy {
namespace {

constexpr int L = kLanes<Scalar>;

// a chain of three bodies: two spheres on the root (shapes 0 and 1), a box on its child (2), a capsule (or a box,
// `box_tip`) on its grandchild (3); the world's own ground plane (4) at height `ground`
ModelBuilder robot(Scalar radius = 0.1, bool box_tip = false, Scalar ground = 0) {
  ModelBuilder world;
  const int root = world.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0, 1, 0)});
  const int child = world.add_body(RigidBody::from_sphere(1, 0.1));
  const int tip = world.add_body(RigidBody::from_sphere(1, 0.1));
  world.add_shape_sphere(root, radius);
  ShapeOptions beside;
  beside.xform.p = Vec3(0.2, 0, 0);
  world.add_shape_sphere(root, 0.1, beside);
  world.add_shape_box(child, Vec3::Constant(0.1));
  if (box_tip)
    world.add_shape_box(tip, Vec3::Constant(0.1));
  else
    world.add_shape_capsule(tip, 0.05, 0.1);
  world.add_ground_plane(ground);
  world.add_joint_free(-1, root);
  world.add_joint_revolute(root, child);
  world.add_joint_revolute(child, tip);
  return world;
}

// the first world of each group where consecutive worlds group while alike(previous, next), up to L of them
template <typename Alike>
std::vector<int> expected_groups(int world_count, Alike alike) {
  std::vector<int> first = {0};
  for (int w = 1; w < world_count; ++w)
    if (!alike(w - 1, w) || w - first.back() == L) first.push_back(w);
  first.push_back(world_count);
  return first;
}

// replicated worlds: groups of L and the rest; each group's lanes read the bodies of their worlds' shapes (lanes
// past the group's, its first world's), every shape the same in all, world 0's shapes read for all groups, the
// worlds' bodies in runs, the root's two shapes in one slot, the ground fixed alike in all lanes and read from
// world 0
TEST(WorldGroups, ReplicatedWorldsFallIntoGroupsOfLanes) {
  const int world_count = 2 * L + 1;
  ModelBuilder builder;
  builder.replicate(robot(), world_count);
  const Model model = builder.finalize();
  const ShapeFilter filter(model, true);
  const WorldShapes shapes(model, filter);
  const WorldGroups groups(model, filter, shapes);
  EXPECT_EQ(groups.first, (std::vector<int>{0, L, 2 * L, world_count}));
  ASSERT_EQ(groups.count(), 3);
  EXPECT_EQ(groups.body_start[2], -1);  // (a world alone)
  EXPECT_EQ(groups.plane_start, (std::vector<int>{0, 1, 2, 2}));
  EXPECT_EQ(groups.slot_start, (std::vector<int>{0, 3, 6, 6}));
  const int ground0 = shapes.world_planes[0][0];
  for (int g = 0; g < 2; ++g) {
    const int first = groups.first[g], count = groups.first[g + 1] - first;
    EXPECT_EQ(groups.same[g], 0b1111u);
    EXPECT_EQ(groups.read_world[g], 0);
    const WorldGroups::BodyRun& run = groups.run[g];
    EXPECT_EQ(run.length, 3);
    for (int l = 0; l < L; ++l) {
      const int w = first + (l < count ? l : 0);
      EXPECT_EQ(run.first[l], 3 * w);
      for (int i = 0; i < 4; ++i) {
        const int s = shapes.world_others[w][i];
        EXPECT_EQ(groups.body[groups.body_start[g] + L * i + l], model.shape_body[s]) << g << " " << l << " " << i;
        EXPECT_EQ(groups.run_place[groups.body_start[g] / L + i], model.shape_body[s] - 3 * w);
      }
      EXPECT_EQ(groups.plane_lanes[L * groups.plane_start[g] + l], shapes.world_planes[w][0]);
    }
    // slots: the root's spheres, the box, the capsule; only the root's (slot 0) and the tip's (slot 2) meet
    const std::uint64_t* slot_shapes = groups.slot_shapes.data() + groups.slot_start[g];
    const std::uint64_t* slot_pairs = groups.slot_pairs.data() + groups.slot_start[g];
    EXPECT_EQ(std::vector<std::uint64_t>(slot_shapes, slot_shapes + 3),
              (std::vector<std::uint64_t>{0b11, 0b100, 0b1000}));
    EXPECT_EQ(std::vector<std::uint64_t>(slot_pairs, slot_pairs + 3), (std::vector<std::uint64_t>{0b100, 0, 0}));
    EXPECT_EQ(groups.plane_shapes[groups.plane_start[g]], 0b1111u);
    EXPECT_EQ(groups.plane_read[groups.plane_start[g]], ground0);
    EXPECT_EQ(groups.plane_still[groups.plane_start[g]], 1);
  }
}

// a world whose tip is a box, not a capsule, stands alone between groups; one whose root sphere is larger joins its
// group, which then reads that shape from each world
TEST(WorldGroups, AWorldWithADifferentShapeBreaksAGroup) {
  enum Kind { kSame, kBoxTip, kLarger };
  const std::vector<Kind> kinds = {kSame, kSame, kBoxTip, kSame, kSame, kSame, kLarger, kSame, kSame};
  ModelBuilder builder;
  for (const Kind kind : kinds) builder.add_builder(robot(kind == kLarger ? 0.2 : 0.1, kind == kBoxTip));
  const Model model = builder.finalize();
  const ShapeFilter filter(model, true);
  const WorldShapes shapes(model, filter);
  const WorldGroups groups(model, filter, shapes);
  const int world_count = static_cast<int>(kinds.size());
  EXPECT_EQ(groups.first,
            expected_groups(world_count, [&](int v, int w) { return (kinds[v] == kBoxTip) == (kinds[w] == kBoxTip); }));
  for (int g = 0; g < groups.count(); ++g) {
    const int first = groups.first[g], count = groups.first[g + 1] - first;
    if (count == 1) {
      EXPECT_EQ(groups.body_start[g], -1);
      continue;
    }
    EXPECT_NE(kinds[first], kBoxTip);
    const bool larger =
        std::find(kinds.begin() + first, kinds.begin() + first + count, kLarger) != kinds.begin() + first + count;
    EXPECT_EQ(groups.same[g], larger ? 0b1110u : 0b1111u) << "group " << g;
    EXPECT_EQ(groups.read_world[g], 0) << "group " << g;  // (the shapes read once are alike to world 0's)
  }
}

// a world whose ground lies lower joins the group: the narrow phase reads one plane's entries for all lanes, but
// each lane's plane is placed where it is
TEST(WorldGroups, APlaneElsewhereIsReadAlikeButPlacedPerLane) {
  ModelBuilder builder;
  builder.add_builder(robot());
  builder.add_builder(robot(0.1, false, -0.5));
  const Model model = builder.finalize();
  const ShapeFilter filter(model, true);
  const WorldShapes shapes(model, filter);
  const WorldGroups groups(model, filter, shapes);
  ASSERT_EQ(groups.first, (std::vector<int>{0, 2}));
  ASSERT_EQ(groups.plane_start, (std::vector<int>{0, 1}));
  EXPECT_EQ(groups.plane_read[0], shapes.world_planes[0][0]);
  EXPECT_EQ(groups.plane_still[0], 0);
  EXPECT_EQ(groups.plane_lanes[0], shapes.world_planes[0][0]);
  EXPECT_EQ(groups.plane_lanes[1], shapes.world_planes[1][0]);
}

// worlds that sweep and prune (more than kMaskedWorldShapes shapes) are each found alone
TEST(WorldGroups, WorldsOfManyShapesStandAlone) {
  ModelBuilder world;
  for (int k = 0; k <= WorldShapes::kMaskedWorldShapes; ++k)
    world.add_shape_sphere(world.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(k, 0, 0)}), 0.1);
  ModelBuilder builder;
  builder.replicate(world, 3);
  const Model model = builder.finalize();
  const ShapeFilter filter(model, true);
  const WorldShapes shapes(model, filter);
  const WorldGroups groups(model, filter, shapes);
  EXPECT_EQ(groups.first, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(groups.body_start, (std::vector<int>{-1, -1, -1}));
}

}  // namespace
}  // namespace novaphy
