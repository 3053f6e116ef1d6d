// WorldShapes: the colliding shapes sorted per world (planes apart, shapes of no world apart, visual shapes left
// out), the order each world meets its planes in, and the pairs' masks of a world of few shapes against the filter.
#include "engine/collision/world_shapes.h"

#include <gtest/gtest.h>

#include "engine/collision/shape_filter.h"
#include "engine/model/builder.h"

namespace novaphy {
namespace {

// a plane of no world (shape 0), two worlds of a sphere, a plane, a visual box and a box (1-4 and 5-8), a sphere
// and a plane of no world (9, 10); world 1's plane moved onto its sphere's body
TEST(WorldShapes, SortsPlanesAndOthersPerWorld) {
  ModelBuilder world;
  world.add_shape_sphere(world.add_body(RigidBody::from_sphere(1, 0.1)), 0.1);
  world.add_ground_plane(-1);
  ShapeOptions visual;
  visual.collision_group = 0;
  world.add_shape_box(0, Vec3::Constant(0.1), visual);
  world.add_shape_box(world.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(1, 0, 0)}), Vec3::Constant(0.1));
  ModelBuilder builder;
  builder.add_ground_plane(-2);
  builder.replicate(world, 2);
  builder.add_shape_sphere(-1, 0.1);
  builder.add_plane(Vec3::UnitX(), -3);
  Model model = builder.finalize();
  ASSERT_EQ(model.shape_count, 11);
  ASSERT_EQ(model.shape_world, (std::vector<int>{-1, 0, 0, 0, 0, 1, 1, 1, 1, -1, -1}));
  model.shape_body[6] = model.shape_body[5];
  const ShapeFilter filter(model, true);
  const WorldShapes shapes(model, filter);
  EXPECT_EQ(shapes.planes, (std::vector<int>{0, 2, 6, 10}));
  EXPECT_EQ(shapes.moving_planes, (std::vector<int>{6}));
  EXPECT_EQ(shapes.world_others, (std::vector<std::vector<int>>{{1, 4}, {5, 8}}));
  EXPECT_EQ(shapes.world_planes, (std::vector<std::vector<int>>{{2}, {6}}));
  EXPECT_EQ(shapes.shared_others, (std::vector<int>{9}));
  EXPECT_EQ(shapes.shared_planes, (std::vector<int>{0, 10}));
  EXPECT_EQ(shapes.shape_part, (std::vector<int>{-1, 0, -1, -1, 0, 1, -1, -1, 1, -1, -1}));
  // each world meets the planes in index order: the first of no world, its own, the second of no world
  for (int w = 0; w < 2; ++w) {
    EXPECT_EQ(shapes.plane_order(w), (std::vector<int>{-1, 0, -2}));
    EXPECT_EQ(shapes.plane_of(w, -1), 0);
    EXPECT_EQ(shapes.plane_of(w, 0), shapes.world_planes[w][0]);
    EXPECT_EQ(shapes.plane_of(w, -2), 10);
  }
}

// a world of few shapes has a mask per shape: bit j where it may collide with the world's shape j after it (an
// excluded pair and a parent with its child left out); a world of more than kMaskedWorldShapes sweeps (no masks)
TEST(WorldShapes, MasksThePairsOfFewShapesAndSweepsMany) {
  ModelBuilder few;
  const int a = few.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = few.add_body(RigidBody::from_sphere(1, 0.1));
  for (int k = 0; k < 3; ++k) few.add_shape_sphere(few.add_body(RigidBody::from_sphere(1, 0.1)), 0.1);
  few.add_shape_sphere(a, 0.1);
  few.add_shape_sphere(b, 0.1);
  few.add_joint_free(-1, a);
  few.add_joint_revolute(a, b);
  few.exclude_shapes(0, 2);
  ModelBuilder many;
  for (int k = 0; k <= WorldShapes::kMaskedWorldShapes; ++k)
    many.add_shape_sphere(many.add_body(RigidBody::from_sphere(1, 0.1)), 0.1);
  ModelBuilder builder;
  builder.add_builder(few);
  builder.add_builder(many);
  const Model model = builder.finalize();
  const ShapeFilter filter(model, true);
  const WorldShapes shapes(model, filter);
  ASSERT_EQ(shapes.world_others[0].size(), 5u);
  EXPECT_EQ(shapes.world_pair_start, (std::vector<int>{0, -1}));
  // shapes 0-2 on bodies of their own, 3 on a, 4 on its child b
  const std::vector<std::uint64_t> expected = {0b11010, 0b11100, 0b11000, 0b00000, 0b00000};
  EXPECT_EQ(shapes.world_pairs, expected);
  for (int i = 0; i < 5; ++i)
    for (int j = i + 1; j < 5; ++j) EXPECT_EQ(expected[i] >> j & 1, filter.may_collide(i, j)) << i << " " << j;
}

}  // namespace
}  // namespace novaphy
