// ShapeFilter: which pairs of shapes may ever collide, from the model's bodies, joints, worlds, groups and masks and
// excluded pairs, and the self_collision option; each case against the rule that decides it.
#include "engine/collision/shape_filter.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "engine/model/builder.h"
#include "test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

// the pairs a < b of the model's shapes that may collide, each asked both ways round
std::set<std::pair<int, int>> colliding_pairs(const Model& model, const ShapeFilter& filter) {
  std::set<std::pair<int, int>> pairs;
  for (int a = 0; a < model.shape_count; ++a)
    for (int b = a + 1; b < model.shape_count; ++b) {
      EXPECT_EQ(filter.may_collide(a, b), filter.may_collide(b, a)) << a << " " << b;
      if (filter.may_collide(a, b)) pairs.insert({a, b});
    }
  return pairs;
}

// the model of the MJCF `text` (written to a file `name` and imported), gravity -z
Model model_of_mjcf(const std::string& name, const std::string& text) {
  const std::string path = test::write_temp_file(name, text);
  ModelBuilder builder(Vec3(0, 0, -9.81));
  builder.add_mjcf(path);
  std::filesystem::remove(path);
  return builder.finalize();
}

// a chain a - b - c of revolute joints, two shapes on a: shapes of one body, a parent and its child never collide;
// a and its grandchild c do, unless self_collision is off
TEST(ShapeFilter, ParentAndChildNeverCollideGrandchildUnlessSelfCollisionIsOff) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.2));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.2));
  const int c = builder.add_body(RigidBody::from_sphere(1, 0.2));
  builder.add_shape_sphere(a, 0.2);  // 0
  builder.add_shape_sphere(a, 0.2);  // 1
  builder.add_shape_sphere(b, 0.2);  // 2
  builder.add_shape_sphere(c, 0.2);  // 3
  builder.add_joint_free(-1, a);
  builder.add_joint_revolute(a, b);
  builder.add_joint_revolute(b, c);
  const Model model = builder.finalize();
  EXPECT_EQ(colliding_pairs(model, ShapeFilter(model, true)), (std::set<std::pair<int, int>>{{0, 3}, {1, 3}}));
  EXPECT_TRUE(colliding_pairs(model, ShapeFilter(model, false)).empty());
}

// a MuJoCo body of two joints is a chain with a massless link between it and its parent: the parent is still its
// parent
TEST(ShapeFilter, ParentThroughMasslessLinks) {
  const Model model = model_of_mjcf("two_joints.xml", R"(
<mujoco>
  <worldbody>
    <body name="a"><freejoint/><geom type="sphere" size="0.1"/>
      <body name="b" pos="0.1 0 0"><joint type="hinge" axis="1 0 0"/><joint type="hinge" axis="0 1 0"/>
        <geom type="sphere" size="0.1"/>
        <body name="c" pos="0.1 0 0"><joint type="hinge"/><geom type="sphere" size="0.1"/></body>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  ASSERT_EQ(model.shape_count, 3);
  ASSERT_GT(model.body_count, 3);  // (the massless link)
  EXPECT_EQ(colliding_pairs(model, ShapeFilter(model, true)), (std::set<std::pair<int, int>>{{0, 2}}));
}

// MuJoCo's weld rule: a body held by a Fixed joint counts as the body it is welded to. A stand welded to the world
// meets no world shape; a tip welded to b never meets b nor b's parent a; c, whose parent is the tip, counts b as
// its parent (Allegro's fingertips: without the rule c met b)
TEST(ShapeFilter, WeldedBodiesCountAsTheBodyTheyAreWeldedTo) {
  const Model model = model_of_mjcf("welded.xml", R"(
<mujoco>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="stand" pos="0 0 0.5"><geom type="box" size="0.1 0.1 0.1"/></body>
    <body name="a" pos="0 0 1"><freejoint/><geom type="sphere" size="0.1"/>
      <body name="b" pos="0.1 0 0"><joint type="hinge"/><geom type="sphere" size="0.1"/>
        <body name="tip" pos="0.1 0 0"><geom type="sphere" size="0.1"/>
          <body name="c" pos="0.1 0 0"><joint type="hinge"/><geom type="sphere" size="0.1"/></body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)");
  ASSERT_EQ(model.shape_count, 6);  // plane, stand, a, b, tip, c
  EXPECT_EQ(colliding_pairs(model, ShapeFilter(model, true)),
            (std::set<std::pair<int, int>>{{0, 2}, {0, 3}, {0, 4}, {0, 5}, {1, 2}, {1, 3}, {1, 4}, {1, 5}, {2, 5}}));
}

// excluded pairs never collide, either way round; groups and masks under the builder's rule (both ways) and MuJoCo's
// (either way); a shape whose group or mask is empty is visual only (under MuJoCo's rule: both)
TEST(ShapeFilter, ExcludedPairsGroupsMasksAndVisualShapes) {
  for (const CollisionFilter rule : {CollisionFilter::GroupAndMask, CollisionFilter::Mujoco}) {
    ModelBuilder builder;
    builder.set_collision_filter(rule);
    ShapeOptions options;
    auto sphere = [&](int group, int mask) {
      options.collision_group = group, options.collision_mask = mask;
      return builder.add_shape_sphere(builder.add_body(RigidBody::from_sphere(1, 0.1)), 0.1, options);
    };
    const int s0 = sphere(1, -1), s1 = sphere(1, -1);
    sphere(1, -1);  // 2
    const int one_way = sphere(2, 0), other_way = sphere(0, 2), visual = sphere(0, 0);
    builder.exclude_shapes(s1, s0);
    const Model model = builder.finalize();
    const ShapeFilter filter(model, true);
    EXPECT_TRUE(filter.excluded(s0, s1));
    EXPECT_TRUE(filter.excluded(s1, s0));
    EXPECT_FALSE(filter.excluded(s0, 2));
    // (3's group meets every mask, but its empty mask takes no group: enough under MuJoCo's rule only)
    const std::set<std::pair<int, int>> both_ways = {{0, 2}, {1, 2}};
    const std::set<std::pair<int, int>> either_way = {{0, 2}, {1, 2}, {0, 3}, {1, 3}, {2, 3}, {3, 4}};
    EXPECT_EQ(colliding_pairs(model, filter), rule == CollisionFilter::Mujoco ? either_way : both_ways);
    EXPECT_FALSE(filter.visual_only(s0));
    EXPECT_EQ(filter.visual_only(one_way), rule == CollisionFilter::GroupAndMask);
    EXPECT_EQ(filter.visual_only(other_way), rule == CollisionFilter::GroupAndMask);
    EXPECT_TRUE(filter.visual_only(visual));
  }
}

// shapes of two worlds never collide; a shape of no world collides with both
TEST(ShapeFilter, WorldsApartSharedShapesMeetEvery) {
  ModelBuilder world;
  world.add_shape_sphere(world.add_body(RigidBody::from_sphere(1, 0.1)), 0.1);
  ModelBuilder builder;
  builder.replicate(world, 2);
  const int ground = builder.add_ground_plane();
  const Model model = builder.finalize();
  ASSERT_EQ(model.shape_world[0], 0);
  ASSERT_EQ(model.shape_world[1], 1);
  ASSERT_EQ(ground, 2);
  ASSERT_EQ(model.shape_world[ground], -1);
  EXPECT_EQ(colliding_pairs(model, ShapeFilter(model, true)), (std::set<std::pair<int, int>>{{0, 2}, {1, 2}}));
}

TEST(ShapeFilter, AnExclusionNamingNoShapeThrows) {
  ModelBuilder builder;
  builder.add_shape_sphere(builder.add_body(RigidBody::from_sphere(1, 0.1)), 0.1);
  builder.add_shape_sphere(builder.add_body(RigidBody::from_sphere(1, 0.1)), 0.1);
  builder.exclude_shapes(0, 1);
  Model model = builder.finalize();
  model.exclude_shape[1] = 5;
  EXPECT_NOVAPHY_ERROR(ShapeFilter(model, true), "exclude_shape[0] names shape 5, the model has 2");
}

}  // namespace
}  // namespace novaphy
