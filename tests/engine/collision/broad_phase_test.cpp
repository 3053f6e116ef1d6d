// The broad phase and the filters: which pairs of shapes a collide tests (masks, groups, MuJoCo's contype and
// conaffinity and exclusions, sweep and prune, worlds alike found a group of lanes at a time), against testing every
// pair.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <set>

#include "engine/collision/pipeline.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/parts/rows.h"
#include "kernels/convex.h"
#include "test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

std::set<std::pair<int, int>> touching_pairs(const Model& model, const CollisionOptions& options = {}) {
  CollisionPipeline pipeline(model, options);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  std::set<std::pair<int, int>> pairs;
  for (int c = 0; c < contacts.contact_count; ++c) {
    const int a = contacts.contact_shape_a[c], b = contacts.contact_shape_b[c];
    pairs.insert({std::min(a, b), std::max(a, b)});
  }
  return pairs;
}

TEST(CollisionPipeline, ShapesOfOneBodyAndOfJointedBodiesDoNotCollide) {
  ModelBuilder builder;
  const int a = builder.add_body(RigidBody::from_sphere(1, 0.2));
  const int b = builder.add_body(RigidBody::from_sphere(1, 0.2));
  const int c = builder.add_body(RigidBody::from_sphere(1, 0.2));
  builder.add_shape_sphere(a, 0.2);  // 0
  builder.add_shape_sphere(a, 0.2);  // 1: same body as 0
  builder.add_shape_sphere(b, 0.2);  // 2: child of a
  builder.add_shape_sphere(c, 0.2);  // 3: grandchild of a
  builder.add_joint_free(-1, a);
  JointOptions options;
  options.dof.axis = Vec3::UnitZ();
  options.parent_xform.p = Vec3(0.1, 0, 0);
  builder.add_joint_revolute(a, b, options);
  builder.add_joint_revolute(b, c, options);
  const Model model = builder.finalize();
  // all four overlap: only a's shapes against its grandchild c may touch
  EXPECT_EQ(touching_pairs(model), (std::set<std::pair<int, int>>{{0, 3}, {1, 3}}));
  CollisionOptions no_self;
  no_self.self_collision = false;
  EXPECT_TRUE(touching_pairs(model, no_self).empty());
}

TEST(CollisionPipeline, GroupsAndMasks) {
  ModelBuilder builder;
  ShapeOptions options;
  std::vector<int> bodies;
  for (int k = 0; k < 3; ++k)
    bodies.push_back(builder.add_body(RigidBody::from_sphere(1, 0.2), Transform{Vec3(0.1 * k, 0, 0)}));
  options.collision_group = 1, options.collision_mask = ~2;  // 0: skips group 2
  builder.add_shape_sphere(bodies[0], 0.2, options);
  options.collision_group = 2, options.collision_mask = -1;  // 1
  builder.add_shape_sphere(bodies[1], 0.2, options);
  options.collision_group = 4, options.collision_mask = -1;  // 2
  builder.add_shape_sphere(bodies[2], 0.2, options);
  EXPECT_EQ(touching_pairs(builder.finalize()), (std::set<std::pair<int, int>>{{0, 2}, {1, 2}}));
}

// the broad phase finds exactly the pairs that testing every pair finds: the masked pairs of a world
// of few shapes (60) and sweep and prune in a world of many (90)
void expect_broad_phase_misses_no_pair(int shapes) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<Scalar> u(-1, 1);
  ModelBuilder builder;
  builder.add_ground_plane(-0.5);
  for (int k = 0; k < shapes; ++k) {
    Transform x = Transform{Vec3(u(rng), u(rng), u(rng))};
    x.q = Quat(u(rng), u(rng), u(rng), u(rng)).normalized();
    const int body = builder.add_body(RigidBody::from_sphere(1, 0.1), x);
    if (k % 3 == 0) builder.add_shape_sphere(body, 0.1 + 0.1 * std::abs(u(rng)));
    if (k % 3 == 1) builder.add_shape_box(body, Vec3(0.1, 0.15, 0.2));
    if (k % 3 == 2) builder.add_shape_capsule(body, 0.05, 0.15);
  }
  const Model model = builder.finalize();
  const auto found = touching_pairs(model);

  // every pair through the narrow phase alone: one pipeline per pair of shapes
  std::set<std::pair<int, int>> expected;
  const State state = model.state();
  for (int a = 0; a < model.shape_count; ++a) {
    for (int b = a + 1; b < model.shape_count; ++b) {
      ModelBuilder pair;
      const int types[2] = {model.shape_type[a], model.shape_type[b]};
      for (int k = 0; k < 2; ++k) {
        const int s = k == 0 ? a : b;
        const int body = model.shape_body[s];
        const Vec3 scale = Eigen::Map<const Vec3>(&model.shape_scale[3 * s]);
        const Transform X = body < 0 ? Transform::from_array(&model.shape_transform[7 * s])
                                     : Transform::from_array(&state.body_q[7 * body]);
        const auto type = static_cast<ShapeType>(types[k]);
        if (type == ShapeType::Plane) {
          pair.add_ground_plane(-0.5);
          continue;
        }
        const int nb = pair.add_body(RigidBody::from_sphere(1, 0.1), X);
        if (type == ShapeType::Sphere) pair.add_shape_sphere(nb, scale.x());
        if (type == ShapeType::Box) pair.add_shape_box(nb, scale);
        if (type == ShapeType::Capsule) pair.add_shape_capsule(nb, scale.x(), scale.y());
      }
      if (!touching_pairs(pair.finalize()).empty()) expected.insert({a, b});
    }
  }
  EXPECT_EQ(found, expected);
  EXPECT_GT(found.size(), 10u);
}

TEST(CollisionPipeline, BroadPhaseMissesNoPairInAWorldOfFewShapes) { expect_broad_phase_misses_no_pair(60); }
TEST(CollisionPipeline, BroadPhaseMissesNoPairInAWorldOfManyShapes) { expect_broad_phase_misses_no_pair(90); }
TEST(CollisionPipeline, PairsSkippedByTheirHoldingBoxesAreThoseTheKernelsFindApart) {
  // a shape on a body moved about a static one of another kind, 300 poses a pair: the pipeline's contacts are the
  // kernel's own (capsule-box by its search, the rest by MPR), so the boxes it first tests hold each kind whole
  // (a mesh: an off-centre wedge of eight points)
  struct Kind {
    ShapeType type;
    ConvexKind convex;
    Vec3 size;  // (radius, half height) of capsules and cylinders, half extents, radii
  };
  const Kind box{ShapeType::Box, ConvexKind::Box, Vec3(0.2, 0.1, 0.15)},
      capsule{ShapeType::Capsule, ConvexKind::Capsule, Vec3(0.05, 0.2, 0)},
      cylinder{ShapeType::Cylinder, ConvexKind::Cylinder, Vec3(0.1, 0.15, 0)},
      ellipsoid{ShapeType::Ellipsoid, ConvexKind::Ellipsoid, Vec3(0.12, 0.2, 0.08)},
      sphere{ShapeType::Sphere, ConvexKind::Sphere, Vec3(0.1, 0, 0)},
      mesh{ShapeType::Mesh, ConvexKind::Hull, Vec3::Zero()};
  const std::vector<Vec3> wedge = {Vec3(0, 0, 0),      Vec3(0.3, 0, 0),       Vec3(0, 0.1, 0),    Vec3(0, 0, 0.15),
                                   Vec3(0.3, 0.02, 0), Vec3(0.05, 0.1, 0.15), Vec3(0.3, 0, 0.15), Vec3(0.02, 0.1, 0)};
  auto add = [&](ModelBuilder& builder, int body, const Kind& kind, const ShapeOptions& options) {
    switch (kind.type) {
      case ShapeType::Mesh: return builder.add_shape_mesh(body, builder.add_mesh(wedge), options);
      case ShapeType::Box: return builder.add_shape_box(body, kind.size, options);
      case ShapeType::Capsule: return builder.add_shape_capsule(body, kind.size.x(), kind.size.y(), options);
      case ShapeType::Cylinder: return builder.add_shape_cylinder(body, kind.size.x(), kind.size.y(), options);
      case ShapeType::Ellipsoid: return builder.add_shape_ellipsoid(body, kind.size, options);
      default: return builder.add_shape_sphere(body, kind.size.x(), options);
    }
  };
  const std::pair<Kind, Kind> pairs[] = {{box, capsule},   {capsule, cylinder}, {box, cylinder}, {cylinder, cylinder},
                                         {box, ellipsoid}, {sphere, cylinder},  {box, mesh},     {mesh, mesh}};
  std::mt19937 rng(12);
  std::normal_distribution<Scalar> g;
  for (const auto& [fixed, moving] : pairs) {
    ModelBuilder builder;
    ShapeOptions placed;
    placed.xform = Transform{Vec3(0, 1, 0), Quat(0.9, 0.2, 0.3, 0.1).normalized()};
    add(builder, -1, fixed, placed);
    const int body = builder.add_body(RigidBody::from_sphere(1, 0.1));
    add(builder, body, moving, {});
    const Model model = builder.finalize();
    CollisionPipeline pipeline(model);
    Contacts contacts = pipeline.contacts();
    State state = model.state();
    // shape s at its body's pose (the world for a static one): a mesh's frame sits at its hull's centre
    auto convex = [&](const Kind& kind, int s, const Transform& body_pose, HullView* hull) {
      const Transform pose = body_pose * Transform::from_array(&model.shape_transform[7 * s]);
      if (kind.type != ShapeType::Mesh) return ConvexShape{kind.convex, pose, kind.size};
      const int m = model.shape_mesh[s], face0 = model.mesh_face_start[m];
      *hull = {&model.mesh_vertex[3 * model.mesh_vertex_start[m]],
               model.mesh_vertex_start[m + 1] - model.mesh_vertex_start[m],
               &model.mesh_face_plane[4 * face0],
               &model.mesh_corner_start[face0],
               model.mesh_corner.data(),
               model.mesh_face_start[m + 1] - face0};
      return ConvexShape{kind.convex, pose, kind.size, hull};
    };
    int touching = 0, apart = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const Transform pose{placed.xform.p + 0.3 * Vec3(g(rng), g(rng), g(rng)),
                           Quat(g(rng), g(rng), g(rng), g(rng)).normalized()};
      for (int k = 0; k < 3; ++k) state.body_q[7 * body + k] = pose.p[k];
      for (int k = 0; k < 4; ++k) state.body_q[7 * body + 3 + k] = pose.q.coeffs()[k];
      pipeline.collide(state, contacts);
      ContactPoint points[kMaxPairContacts];
      HullView hull_a, hull_b;
      const Scalar margin = pipeline.options().margin;
      const int expected =
          fixed.type == ShapeType::Box && moving.type == ShapeType::Capsule
              ? collide_capsule_box(pose, moving.size.x(), moving.size.y(), placed.xform, fixed.size, margin, points)
              : collide_convex(convex(fixed, 0, Transform{}, &hull_a), convex(moving, 1, pose, &hull_b), margin,
                               points);
      ASSERT_EQ(contacts.contact_count, expected)
          << static_cast<int>(fixed.type) << "-" << static_cast<int>(moving.type) << " trial " << trial;
      (expected > 0 ? touching : apart) += 1;
    }
    EXPECT_GT(touching, 15) << static_cast<int>(fixed.type) << "-" << static_cast<int>(moving.type);
    EXPECT_GT(apart, 15) << static_cast<int>(fixed.type) << "-" << static_cast<int>(moving.type);
  }
}

// worlds alike have their boxes, overlapping pairs and planes found a group of kLanes at a time: each
// world of a batch finds the contacts it finds alone (a world alone is a group of one, on the scalar
// path), bit for bit. The batch mixes worlds of one robot with a copy whose ball is larger (alike, not
// the same size: its sizes are read per world), a robot of one shape fewer (not alike: a group apart)
// and one whose shapes sit on its bodies in reverse order (alike, but its group has no common run of
// bodies: read number by number; two shapes on one body in the others' worlds are on two in its); one body has
// two shapes (the broad phase joins a body's shapes' boxes); each world has its floor and a box on no body, and a
// tilted plane of no world cuts through them all
TEST(CollisionPipeline, WorldsFoundTogetherFindWhatEachFindsAlone) {
  // (soft: the floor and the spheres of MuJoCo's softness with a 20 cm margin, where the others' rigid pairs make
  // contacts within the pipeline's 1 cm)
  auto robot = [](Scalar radius, bool capsule, bool reversed, bool soft = false) {
    ModelBuilder world;
    ShapeOptions softness;
    softness.solref = {0.02, 1};
    softness.margin = 0.2;
    world.add_ground_plane(0, soft ? softness : ShapeOptions{});
    ShapeOptions step;  // a step in the floor, on no body, that the lowest bodies reach
    step.xform.p = Vec3(0.1, 0, 0);
    world.add_shape_box(-1, Vec3(0.15, 0.25, 0.15), step);
    std::mt19937 rng(9);
    std::uniform_real_distribution<Scalar> u(-0.25, 0.25);
    int body[7];
    for (int k = 0; k < 7; ++k) {
      Transform x{Vec3(u(rng), 0.2 + std::abs(u(rng)), u(rng))};
      x.q = Quat(1 + u(rng), u(rng), u(rng), u(rng)).normalized();
      body[k] = world.add_body(RigidBody::from_sphere(1, 0.1), x);
    }
    for (int k = 0; k < 7; ++k) {
      const int b = body[reversed ? 6 - k : k];
      if (k % 3 == 0) world.add_shape_sphere(b, radius, soft ? softness : ShapeOptions{});
      if (k % 3 == 1) world.add_shape_box(b, Vec3(0.12, 0.08, 0.1));
      if (k % 3 == 2 && (capsule || k < 5)) world.add_shape_capsule(b, 0.06, 0.1);
    }
    ShapeOptions beside;  // a second shape on a body: the broad phase joins a body's shapes' boxes
    beside.xform.p = Vec3(0.25, 0, 0);
    world.add_shape_sphere(body[1], 0.12, beside);
    return world;
  };
  const ModelBuilder kinds[5] = {robot(0.15, true, false), robot(0.2, true, false), robot(0.15, false, false),
                                 robot(0.15, true, true), robot(0.15, true, false, true)};
  // (groups of worlds alike: 0-7, then 11-18 of rigid spheres and 19-26 of soft ones, each group's narrow phase
  // reading its own)
  const int kind_of[27] = {0, 0, 0, 1, 0, 4, 0, 0, 0, 3, 2, 0, 0, 0, 0, 0, 0, 0, 0, 4, 4, 4, 4, 4, 4, 4, 4};
  ModelBuilder builder;
  for (const int k : kind_of) builder.add_builder(kinds[k], Transform{}, -1);
  const Vec3 tilted = Vec3(0.3, 1, 0.1).normalized();
  builder.add_plane(tilted, 0.3);
  const Model model = builder.finalize();
  ASSERT_EQ(model.world_count, 27);
  // each world's bodies moved apart a little, differently, so that each world meets its own pairs
  std::mt19937 rng(3);
  std::uniform_real_distribution<Scalar> u(-0.06, 0.06);
  State state = model.state();
  for (int b = 0; b < model.body_count; ++b)
    for (int k = 0; k < 3; ++k) state.body_q[7 * b + k] += u(rng);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(state, contacts);
  int body0 = 0, shape0 = 0, checked = 0, tilted_plane = 0, step_box = 0, beside = 0;
  int soft_gap[2] = {};  // world 5's, and those of worlds 19-26
  for (int w = 0; w < model.world_count; ++w) {
    ModelBuilder one;
    one.add_builder(kinds[kind_of[w]]);
    one.add_plane(tilted, 0.3);
    const Model alone = one.finalize();
    const int own_shapes = alone.shape_count - 1;  // the tilted plane last in both
    auto in_alone = [&](int s) { return s == model.shape_count - 1 ? own_shapes : s - shape0; };
    State s = alone.state();
    std::copy_n(&state.body_q[7 * body0], 7 * alone.body_count, s.body_q.begin());
    CollisionPipeline p(alone);
    Contacts c = p.contacts();
    p.collide(s, c);
    // the batch's contacts of world w, in their order
    std::vector<int> mine;
    for (int k = 0; k < contacts.contact_count; ++k)
      if (std::max(model.shape_world[contacts.contact_shape_a[k]], model.shape_world[contacts.contact_shape_b[k]]) == w)
        mine.push_back(k);
    ASSERT_EQ(static_cast<int>(mine.size()), c.contact_count) << "world " << w;
    for (int k = 0; k < c.contact_count; ++k) {
      const int m = mine[k];
      EXPECT_EQ(in_alone(contacts.contact_shape_a[m]), c.contact_shape_a[k]) << "world " << w << " contact " << k;
      EXPECT_EQ(in_alone(contacts.contact_shape_b[m]), c.contact_shape_b[k]) << "world " << w << " contact " << k;
      tilted_plane += c.contact_shape_a[k] == own_shapes;
      step_box += c.contact_shape_a[k] == 1 || c.contact_shape_b[k] == 1;            // (after the floor: shape 1)
      beside += c.contact_shape_b[k] == own_shapes - 1 && c.contact_shape_a[k] > 1;  // (with a robot's shape)
      EXPECT_EQ(contacts.contact_feature[m], c.contact_feature[k]);
      EXPECT_EQ(contacts.contact_depth[m], c.contact_depth[k]) << "world " << w << " contact " << k;
      soft_gap[w >= 19] += kind_of[w] == 4 && c.contact_depth[k] < -0.01;  // (further apart than a rigid pair's margin)
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(contacts.contact_point[3 * m + i], c.contact_point[3 * k + i]) << "world " << w << " contact " << k;
        EXPECT_EQ(contacts.contact_normal[3 * m + i], c.contact_normal[3 * k + i]) << "world " << w << " contact " << k;
      }
    }
    checked += c.contact_count;
    body0 += alone.body_count;
    shape0 += own_shapes;
  }
  EXPECT_EQ(checked, contacts.contact_count);
  EXPECT_GT(checked, 13 * 4);
  EXPECT_GT(tilted_plane, 13);
  EXPECT_GT(step_box, 13);
  EXPECT_GT(beside, 13);
  EXPECT_GT(soft_gap[0], 0);
  EXPECT_GT(soft_gap[1], 0);
}

// worlds alike but for their floors' heights are found together, each sphere against its own world's floor
// (a group reads one plane's pose for all its worlds only where their planes are at one place)
TEST(CollisionPipeline, WorldsFindTheirOwnFloorsWhereTheFloorsDiffer) {
  constexpr int kWorlds = 12;
  ModelBuilder builder;
  for (int w = 0; w < kWorlds; ++w) {
    ModelBuilder world;
    const Scalar floor = 0.02 * w;
    world.add_ground_plane(floor);
    world.add_shape_sphere(world.add_body(RigidBody(), Transform{Vec3(0, floor + 0.1 - 0.004, 0)}), 0.1);
    world.add_shape_sphere(world.add_body(RigidBody(), Transform{Vec3(1, floor + 0.5, 0)}), 0.1);
    builder.add_builder(world, Transform{}, -1);
  }
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  ASSERT_EQ(contacts.contact_count, kWorlds);
  for (int c = 0; c < kWorlds; ++c) {
    const int plane = contacts.contact_shape_a[c], sphere = contacts.contact_shape_b[c];
    EXPECT_EQ(model.shape_world[plane], c);
    EXPECT_EQ(model.shape_world[sphere], c);
    EXPECT_NEAR(contacts.contact_depth[c], 0.004, 1e-12) << "world " << c;
    EXPECT_NEAR(contacts.contact_point[3 * c + 1], 0.02 * c - 0.002, 1e-12) << "world " << c;
  }
}

TEST(CollisionPipeline, ASoftShapesMarginLeavesRigidPairsTheirs) {
  // a rigid sphere 3 cm above a rigid floor beside soft spheres of a 5 cm margin on a soft box: the broad phase
  // reaches 5 cm, the rigid pair makes its contacts within the pipeline's 1 cm only
  ModelBuilder builder;
  builder.add_ground_plane();
  builder.add_shape_sphere(builder.add_body(RigidBody(), Transform{Vec3(0, 0.13, 0)}), 0.1);
  ShapeOptions soft;
  soft.solref = {0.02, 1};
  soft.margin = 0.05;
  soft.xform.p = Vec3(3, 0.5, 0);
  builder.add_shape_box(-1, Vec3(0.5, 0.5, 0.5), soft);
  soft.xform.p = Vec3::Zero();
  builder.add_shape_sphere(builder.add_body(RigidBody(), Transform{Vec3(3, 1.13, 0)}), 0.1, soft);
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  EXPECT_EQ(pipeline.options().margin, 0.01);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  ASSERT_EQ(contacts.contact_count, 1);  // the soft pair, 3 cm apart
  EXPECT_EQ(std::max(contacts.contact_body_a[0], contacts.contact_body_b[0]), 1);
  EXPECT_NEAR(contacts.contact_depth[0], -0.03, 1e-12);
}

// a body's shape far from its other shape meets a shape of another body in every world of a group found together
// (the broad phase tests two bodies' shapes where the boxes joining each body's shapes overlap)
TEST(CollisionPipeline, ABodysShapesAreJoinedInTheBroadPhase) {
  ModelBuilder world;
  const int a = world.add_body(RigidBody::from_sphere(1, 0.1), Transform{});
  world.add_shape_box(a, Vec3(0.1, 0.1, 0.1));
  ShapeOptions far;
  far.xform.p = Vec3(1, 0, 0);
  world.add_shape_sphere(a, 0.1, far);
  const int b = world.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(1.15, 0, 0)});
  world.add_shape_sphere(b, 0.1);
  ModelBuilder builder;
  const int worlds = 2 * kLanes<Scalar> + 1;
  for (int w = 0; w < worlds; ++w) builder.add_builder(world, Transform{Vec3(0, 0, 3.0 * w)}, -1);
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  ASSERT_EQ(contacts.contact_count, worlds);
  for (int w = 0; w < worlds; ++w) {
    EXPECT_EQ(contacts.contact_shape_a[w], 3 * w + 1) << "world " << w;
    EXPECT_EQ(contacts.contact_shape_b[w], 3 * w + 2) << "world " << w;
    EXPECT_NEAR(contacts.contact_depth[w], 0.05, 1e-12) << "world " << w;
  }
}

// MuJoCo's filter on an imported file: a pair collides when either shape's contype meets the other's
// conaffinity (where the builder's rule needs both); <exclude> keeps two bodies apart; a geom that collides with
// nothing is visual and not reported
TEST(CollisionPipelineFiltering, MujocosContypeConaffinityAndExclusions) {
  const std::string path = test::write_temp_file("filtered.xml", R"(
<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1"><freejoint/><geom type="sphere" size="0.1" contype="1" conaffinity="0"/></body>
    <body name="b" pos="0.15 0 1"><freejoint/><geom type="sphere" size="0.1" contype="0" conaffinity="1"/></body>
    <body name="c" pos="0 3 1"><freejoint/><geom type="sphere" size="0.1" contype="2" conaffinity="2"/></body>
    <body name="d" pos="0.15 3 1"><freejoint/><geom type="sphere" size="0.1" contype="1" conaffinity="1"/></body>
    <body name="e" pos="0 6 1"><freejoint/><geom type="box" size="0.1 0.1 0.1"/>
      <geom type="cylinder" size="0.05 0.1" contype="0" conaffinity="0"/></body>
    <body name="f" pos="0.15 6 1"><freejoint/><geom type="box" size="0.1 0.1 0.1"/>
      <geom name="can" type="cylinder" size="0.05 0.1" pos="0 0 0.5"/></body>
  </worldbody>
  <contact><exclude body1="e" body2="f"/></contact>
</mujoco>)");
  ModelBuilder builder(Vec3(0, 0, -9.81));
  const std::vector<std::string> warnings = builder.add_mjcf(path);
  std::string all;
  for (const std::string& w : warnings) all += w + "\n";
  EXPECT_TRUE(all.empty()) << all;
  const Model model = builder.finalize();
  EXPECT_EQ(model.collision_filter, CollisionFilter::Mujoco);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  std::set<std::pair<int, int>> touching;
  for (int k = 0; k < contacts.contact_count; ++k)
    touching.insert({std::min(contacts.contact_body_a[k], contacts.contact_body_b[k]),
                     std::max(contacts.contact_body_a[k], contacts.contact_body_b[k])});
  EXPECT_EQ(touching, (std::set<std::pair<int, int>>{{0, 1}}));  // c-d filtered, e-f excluded
  std::filesystem::remove(path);

  // the builder's rule on the same pair of masks: both ways needed
  ModelBuilder own;
  ShapeOptions one_way, other_way;
  one_way.collision_group = 1, one_way.collision_mask = 0;
  other_way.collision_group = 0, other_way.collision_mask = 1;
  own.add_shape_sphere(own.add_body(RigidBody::from_sphere(1, 0.1)), 0.1, one_way);
  own.add_shape_sphere(own.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0.15, 0, 0)}), 0.1, other_way);
  const Model mine = own.finalize();
  EXPECT_EQ(mine.collision_filter, CollisionFilter::GroupAndMask);
  CollisionPipeline strict(mine);
  Contacts none = strict.contacts();
  strict.collide(mine.state(), none);
  EXPECT_EQ(none.contact_count, 0);
}

TEST(CollisionPipelineFiltering, ExcludedShapePairsNeverCollideInEveryWorld) {
  ModelBuilder world;
  const int a = world.add_body(RigidBody::from_sphere(1, 0.1));
  const int b = world.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0.15, 0, 0)});
  const int c = world.add_body(RigidBody::from_sphere(1, 0.1), Transform{Vec3(0.075, 0.1, 0)});
  for (const int body : {a, b, c}) world.add_shape_sphere(body, 0.1);
  world.exclude_bodies(a, b);
  EXPECT_NOVAPHY_ERROR(world.exclude_shapes(0, 7), "exclude_shapes: shape index 7 out of range [0, 3)");
  EXPECT_NOVAPHY_ERROR(world.exclude_bodies(a, 9), "exclude_bodies: body index 9 out of range [-1, 3)");
  ModelBuilder worlds;
  worlds.replicate(world, 3);
  const Model model = worlds.finalize();
  ASSERT_EQ(model.exclude_count, 3);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  for (int k = 0; k < contacts.contact_count; ++k) {
    const int x = contacts.contact_body_a[k] % 3, y = contacts.contact_body_b[k] % 3;
    EXPECT_FALSE((x == a && y == b) || (x == b && y == a)) << "contact " << k;
  }
  EXPECT_EQ(contacts.contact_count, 3 * 2);  // a-c and b-c in each world
}

}  // namespace
}  // namespace novaphy
