#include "engine/collision/pipeline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <set>

#include "engine/import/mjcf_import.h"
#include "engine/model/builder.h"
#include "engine/solver/parts/rows.h"
#include "kernels/convex.h"
#include "test_support.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

// 16 contacts (four boxes on the ground, four corners each) into a buffer of 10: by default it grows (the same
// contacts as a large enough buffer, the arrays it replaced still readable); Raise throws naming the capacity
// needed and leaves the buffer as it was; Drop keeps the first 10 and counts the rest
TEST(CollisionPipeline, CapacityOverflowGrowsRaisesOrDrops) {
  ModelBuilder builder;
  builder.add_ground_plane();
  for (int k = 0; k < 4; ++k)
    builder.add_shape_box(builder.add_body(RigidBody(), Transform{Vec3(k, 0.1, 0)}), Vec3::Constant(0.2));
  const Model model = builder.finalize();
  CollisionPipeline roomy(model);
  Contacts all = roomy.contacts();
  roomy.collide(model.state(), all);
  ASSERT_EQ(all.contact_count, 16);

  CollisionOptions options;
  options.contact_capacity = 10;
  CollisionPipeline growing(model, options);
  Contacts contacts = growing.contacts();
  contacts.contact_depth.assign(10, 7.0);
  const Scalar* before = contacts.contact_depth.data();
  growing.collide(model.state(), contacts);
  EXPECT_EQ(contacts.contact_count, 16);
  EXPECT_EQ(contacts.contact_dropped, 0);
  EXPECT_EQ(contacts.contact_capacity, 20);
  EXPECT_EQ(contacts.contact_depth.size(), 20u);
  EXPECT_TRUE(std::equal(all.contact_depth.begin(), all.contact_depth.begin() + 16, contacts.contact_depth.begin()));
  EXPECT_TRUE(std::equal(all.contact_point.begin(), all.contact_point.begin() + 48, contacts.contact_point.begin()));
  EXPECT_EQ(before[9], 7.0);                 // the replaced array is kept (a numpy view of it stays valid)
  growing.collide(model.state(), contacts);  // a grown buffer goes on with the same pipeline
  EXPECT_EQ(contacts.contact_count, 16);

  options.on_overflow = ContactOverflow::Raise;
  CollisionPipeline raising(model, options);
  Contacts small = raising.contacts();
  EXPECT_NOVAPHY_ERROR(raising.collide(model.state(), small),
                       "contact capacity 10 is too small: collide found 16 contacts (make the pipeline with "
                       "contact_capacity >= 16, or on_overflow Grow); the buffer is left as it was");
  EXPECT_EQ(small.contact_count, 0);
  EXPECT_EQ(small.contact_capacity, 10);

  options.on_overflow = ContactOverflow::Drop;
  CollisionPipeline dropping(model, options);
  Contacts dropped = dropping.contacts();
  dropping.collide(model.state(), dropped);
  EXPECT_EQ(dropped.contact_count, 10);
  EXPECT_EQ(dropped.contact_dropped, 6);
  EXPECT_EQ(dropped.contact_capacity, 10);
}

TEST(CollisionPipeline, PreviousImpulsesAreFoundByFeature) {
  ModelBuilder builder;
  builder.add_ground_plane();
  builder.add_shape_box(builder.add_body(RigidBody(), Transform{Vec3(0, 0.19, 0)}), Vec3::Constant(0.2));
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(model.state(), contacts);
  ASSERT_EQ(contacts.contact_count, 4);
  for (int c = 0; c < 4; ++c) contacts.contact_impulse[3 * c + 1] = 10 + c;
  const std::vector<int> features(contacts.contact_feature.begin(), contacts.contact_feature.begin() + 4);
  pipeline.collide(model.state(), contacts);
  for (int c = 0; c < 4; ++c) {
    const Scalar* previous = contacts.previous(c);
    ASSERT_NE(previous, nullptr);
    const int before = std::find(features.begin(), features.end(), contacts.contact_feature[c]) - features.begin();
    EXPECT_EQ(previous[1], 10 + before);
  }
}

TEST(CollisionPipeline, PreviousImpulsesFollowTheirContactsWhenTheListChanges) {
  // three spheres on a floor; the middle one lifted off, then put back: the others keep their
  // impulses though their places in the buffer move, and the returning contact starts without one
  ModelBuilder builder;
  builder.add_ground_plane();
  std::vector<int> spheres;
  for (int k = 0; k < 3; ++k) {
    spheres.push_back(builder.add_body(RigidBody(), Transform{Vec3(k, 0.09, 0)}));
    builder.add_shape_sphere(spheres.back(), 0.1);
  }
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  State state = model.state();
  auto mark = [&] {  // impulse y = 10 + the sphere's body
    for (int c = 0; c < contacts.contact_count; ++c)
      contacts.contact_impulse[3 * c + 1] = 10 + contacts.contact_body_b[c];
  };
  auto expect_marked = [&](int missing) {
    for (int c = 0; c < contacts.contact_count; ++c) {
      const Scalar* previous = contacts.previous(c);
      if (contacts.contact_body_b[c] == missing) {
        EXPECT_EQ(previous, nullptr);
        continue;
      }
      ASSERT_NE(previous, nullptr) << "contact " << c;
      EXPECT_EQ(previous[1], 10 + contacts.contact_body_b[c]);
    }
  };
  pipeline.collide(state, contacts);
  ASSERT_EQ(contacts.contact_count, 3);
  mark();
  state.body_q[7 * spheres[1] + 1] = 1;
  pipeline.collide(state, contacts);
  ASSERT_EQ(contacts.contact_count, 2);
  expect_marked(-1);
  mark();
  state.body_q[7 * spheres[1] + 1] = 0.09;
  pipeline.collide(state, contacts);
  ASSERT_EQ(contacts.contact_count, 3);
  EXPECT_EQ(contacts.contact_body_b[1], spheres[1]);  // back in the middle of the buffer
  expect_marked(spheres[1]);
}

TEST(CollisionPipeline, PreviousImpulsesFollowTheirContactsInManyWorldsOnAnyThreads) {
  // 120 worlds of three spheres on their floor, and a sphere of no world on a box of no world (the list's last
  // run): more contacts than one run of matching. A sphere of three worlds lifted off, then put back: every other
  // contact keeps its impulse, the returning ones start without one, and where each was matched is the same on one,
  // two and three threads
  ModelBuilder world, builder;
  world.add_ground_plane();
  for (int k = 0; k < 3; ++k) world.add_shape_sphere(world.add_body(RigidBody(), Transform{Vec3(k, 0.09, 0)}), 0.1);
  builder.replicate(world, 120);
  ShapeOptions box;
  box.xform = Transform{Vec3(0, 5, 0)};
  builder.add_shape_box(-1, Vec3(0.5, 0.5, 0.5), box);
  builder.add_shape_sphere(builder.add_body(RigidBody(), Transform{Vec3(0, 5.59, 0)}), 0.1);
  const Model model = builder.finalize();
  const std::vector<int> lifted = {1 * 3 + 1, 64 * 3 + 0, 119 * 3 + 2};  // bodies: a world's three in order
  auto run = [&](int threads) {
    CollisionOptions options;
    options.num_threads = threads;
    CollisionPipeline pipeline(model, options);
    Contacts contacts = pipeline.contacts();
    State state = model.state();
    auto sphere = [&](int c) { return std::max(contacts.contact_body_a[c], contacts.contact_body_b[c]); };
    auto mark = [&] {  // impulse y = 10 + the sphere's body
      for (int c = 0; c < contacts.contact_count; ++c) contacts.contact_impulse[3 * c + 1] = 10 + sphere(c);
    };
    auto expect_marked = [&](const std::vector<int>& missing) {
      for (int c = 0; c < contacts.contact_count; ++c) {
        const Scalar* previous = contacts.previous(c);
        if (std::count(missing.begin(), missing.end(), sphere(c))) {
          EXPECT_EQ(previous, nullptr) << "contact " << c;
          continue;
        }
        ASSERT_NE(previous, nullptr) << "contact " << c << ", " << threads << " threads";
        EXPECT_EQ(previous[1], 10 + sphere(c));
      }
    };
    std::vector<int> matched;
    pipeline.collide(state, contacts);
    EXPECT_EQ(contacts.contact_count, 361);
    mark();
    for (const int b : lifted) state.body_q[7 * b + 1] = 1;
    pipeline.collide(state, contacts);
    EXPECT_EQ(contacts.contact_count, 358);
    expect_marked({});
    matched.insert(matched.end(), contacts.previous_match.begin(),
                   contacts.previous_match.begin() + contacts.contact_count);
    mark();
    for (const int b : lifted) state.body_q[7 * b + 1] = 0.09;
    pipeline.collide(state, contacts);
    EXPECT_EQ(contacts.contact_count, 361);
    expect_marked(lifted);
    matched.insert(matched.end(), contacts.previous_match.begin(),
                   contacts.previous_match.begin() + contacts.contact_count);
    return matched;
  };
  const std::vector<int> one = run(1);
  EXPECT_EQ(run(2), one);
  EXPECT_EQ(run(3), one);
}

TEST(CollisionPipeline, ABufferWithoutItsWarmStartBookkeepingGetsIt) {
  // a buffer copied field by field (the contact arrays only) still warm starts after one collide
  ModelBuilder builder;
  builder.add_ground_plane();
  builder.add_shape_sphere(builder.add_body(RigidBody(), Transform{Vec3(0, 0.09, 0)}), 0.1);
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  contacts.previous_key.clear();
  contacts.previous_impulse.clear();
  contacts.previous_match.clear();
  pipeline.collide(model.state(), contacts);
  ASSERT_EQ(contacts.contact_count, 1);
  EXPECT_EQ(contacts.previous(0), nullptr);
  contacts.contact_impulse[1] = 3;
  pipeline.collide(model.state(), contacts);
  ASSERT_NE(contacts.previous(0), nullptr);
  EXPECT_EQ(contacts.previous(0)[1], 3);
}

TEST(CollisionPipeline, CountSerialTimeSplitsEachCollideOnlyWhenOn) {
  // 40 worlds of a sphere on a floor on two threads: the collides' wall time, and within it their region's
  ModelBuilder world, builder;
  world.add_ground_plane();
  world.add_shape_sphere(world.add_body(RigidBody(), Transform{Vec3(0, 0.09, 0)}), 0.1);
  builder.replicate(world, 40);
  const Model model = builder.finalize();
  for (const bool on : {false, true}) {
    CollisionOptions options;
    options.num_threads = 2;
    options.count_serial_time = on;
    CollisionPipeline pipeline(model, options);
    Contacts contacts = pipeline.contacts();
    for (int k = 0; k < 3; ++k) pipeline.collide(model.state(), contacts);
    const SerialSeconds& t = pipeline.serial_seconds();
    if (!on) {
      EXPECT_EQ(t.steps, 0);
      EXPECT_EQ(t.step, 0);
      continue;
    }
    EXPECT_EQ(t.steps, 3);
    EXPECT_GT(t.parallel, 0);
    EXPECT_LT(t.parallel, t.step);
    pipeline.reset_serial_seconds();
    EXPECT_EQ(pipeline.serial_seconds().steps, 0);
  }
}

TEST(CollisionPipeline, ThreadsFindTheSameContactsInTheSameOrder) {
  // 40 worlds of a floor and a pile of touching bodies: each world's pairs and each plane's contacts
  // found on whichever thread, written in world and plane order, so the buffer is the same bit for bit;
  // with a capacity too small, the same first contacts are kept and the same number dropped
  std::mt19937 rng(4);
  std::uniform_real_distribution<Scalar> u(-0.3, 0.3);
  ModelBuilder world;
  world.add_ground_plane();
  for (int k = 0; k < 6; ++k) {
    const int body = world.add_body(RigidBody(), Transform{Vec3(u(rng), 0.15 + 0.5 * std::abs(u(rng)), u(rng))});
    if (k % 2 == 0) world.add_shape_box(body, Vec3::Constant(0.15));
    if (k % 2 == 1) world.add_shape_sphere(body, 0.15);
  }
  ModelBuilder builder;
  builder.replicate(world, 40);
  const Model model = builder.finalize();
  auto collide = [&](int threads, int capacity, ContactOverflow overflow) {
    CollisionOptions options;
    options.num_threads = threads;
    options.contact_capacity = capacity;
    options.on_overflow = overflow;
    CollisionPipeline pipeline(model, options);
    Contacts contacts = pipeline.contacts();
    pipeline.collide(model.state(), contacts);
    return contacts;
  };
  // a roomy buffer, one that grows and one that drops
  for (const auto& [capacity, overflow] : {std::pair{0, ContactOverflow::Grow}, std::pair{300, ContactOverflow::Grow},
                                           std::pair{300, ContactOverflow::Drop}}) {
    const Contacts one = collide(1, capacity, overflow);
    ASSERT_GT(one.contact_count, 200);
    for (const int threads : {2, 3}) {
      const Contacts many = collide(threads, capacity, overflow);
      ASSERT_EQ(many.contact_count, one.contact_count) << threads << " threads";
      EXPECT_EQ(many.contact_dropped, one.contact_dropped);
      const int n = one.contact_count;
      EXPECT_TRUE(
          std::equal(one.contact_shape_a.begin(), one.contact_shape_a.begin() + n, many.contact_shape_a.begin()));
      EXPECT_TRUE(
          std::equal(one.contact_shape_b.begin(), one.contact_shape_b.begin() + n, many.contact_shape_b.begin()));
      EXPECT_TRUE(
          std::equal(one.contact_feature.begin(), one.contact_feature.begin() + n, many.contact_feature.begin()));
      EXPECT_TRUE(std::equal(one.contact_point.begin(), one.contact_point.begin() + 3 * n, many.contact_point.begin()));
      EXPECT_TRUE(
          std::equal(one.contact_normal.begin(), one.contact_normal.begin() + 3 * n, many.contact_normal.begin()));
      EXPECT_TRUE(std::equal(one.contact_depth.begin(), one.contact_depth.begin() + n, many.contact_depth.begin()));
    }
  }
  EXPECT_GT(collide(2, 300, ContactOverflow::Drop).contact_dropped, 0);
  EXPECT_EQ(collide(2, 300, ContactOverflow::Grow).contact_count, collide(1, 0, ContactOverflow::Grow).contact_count);
}

// static shapes of no world meet every world's shapes, each world's in its pass: a box under 40 worlds'
// spheres touches each sphere once, the same contacts in the same order on one thread and two
TEST(CollisionPipeline, ShapesOfNoWorldMeetEveryWorld) {
  ModelBuilder world, builder;
  const int ball = world.add_body(RigidBody::from_sphere(1, 0.2), Transform{Vec3(0, 0.5, 0)});
  world.add_shape_sphere(ball, 0.2);
  builder.replicate(world, 40);
  ShapeOptions placed;
  placed.xform.p = Vec3(0, 0, 0);
  const int floor_box = builder.add_shape_box(-1, Vec3(1, 0.35, 1), placed);
  placed.xform.p = Vec3(5, 0, 0);
  builder.add_shape_box(-1, Vec3(1, 0.35, 1), placed);  // touches nothing
  const Model model = builder.finalize();
  auto collide = [&](int threads) {
    CollisionOptions options;
    options.num_threads = threads;
    CollisionPipeline pipeline(model, options);
    Contacts contacts = pipeline.contacts();
    pipeline.collide(model.state(), contacts);
    return contacts;
  };
  const Contacts one = collide(1), two = collide(2);
  ASSERT_EQ(one.contact_count, 40);
  std::set<int> spheres;
  for (int c = 0; c < one.contact_count; ++c) {
    const int a = one.contact_shape_a[c], b = one.contact_shape_b[c];
    EXPECT_TRUE(a == floor_box || b == floor_box) << "contact " << c;
    spheres.insert(a == floor_box ? b : a);
  }
  EXPECT_EQ(spheres.size(), 40u);
  ASSERT_EQ(two.contact_count, one.contact_count);
  EXPECT_TRUE(std::equal(one.contact_shape_a.begin(), one.contact_shape_a.begin() + 40, two.contact_shape_a.begin()));
  EXPECT_TRUE(std::equal(one.contact_shape_b.begin(), one.contact_shape_b.begin() + 40, two.contact_shape_b.begin()));
}

TEST(CollisionPipelineErrors, BadOptions) {
  ModelBuilder builder;
  builder.add_body(RigidBody());
  const Model model = builder.finalize();
  CollisionOptions options;
  options.contact_capacity = -1;
  EXPECT_NOVAPHY_ERROR(CollisionPipeline(model, options), "contact_capacity must be >= 0, got -1");
  options = {};
  options.margin = std::nan("");
  EXPECT_NOVAPHY_ERROR(CollisionPipeline(model, options), "margin must be finite and >= 0, got nan");
  options = {};
  options.num_threads = -1;
  EXPECT_NOVAPHY_ERROR(CollisionPipeline(model, options), "num_threads must be >= 0 (0: OpenMP's default), got -1");
}

}  // namespace
}  // namespace novaphy

namespace novaphy {
namespace {

TEST(ContactFriction, MujocosRuleMatchesMujocosContactsPairByPair) {
  // overlapping sphere pairs: equal priorities (the larger friction), a higher priority with the lower friction
  // (it decides), condim 1 against 3 (the larger: with friction), condim 1 of the higher priority (frictionless);
  // each contact's friction against MuJoCo 2.2.2's own contact of the same two geoms (friction[0], or 0 where
  // its dim is 1)
  const std::string path = test::write_temp_file("friction_pairs.xml", R"(
<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body pos="0 0 0"><freejoint/><geom type="sphere" size="0.1" friction="0.3"/></body>
    <body pos="0.15 0 0"><freejoint/><geom type="sphere" size="0.1" friction="0.9"/></body>
    <body pos="0 1 0"><freejoint/><geom type="sphere" size="0.1" friction="0.2" priority="1"/></body>
    <body pos="0.15 1 0"><freejoint/><geom type="sphere" size="0.1" friction="0.7"/></body>
    <body pos="0 2 0"><freejoint/><geom type="sphere" size="0.1" friction="0.4" condim="1"/></body>
    <body pos="0.15 2 0"><freejoint/><geom type="sphere" size="0.1" friction="0.5"/></body>
    <body pos="0 3 0"><freejoint/><geom type="sphere" size="0.1" friction="0.6" condim="1" priority="2"/></body>
    <body pos="0.15 3 0"><freejoint/><geom type="sphere" size="0.1" friction="0.8" priority="1"/></body>
  </worldbody>
</mujoco>)");
  ModelBuilder builder;
  const MujocoImport import = import_mjcf(builder, path);
  ASSERT_TRUE(import.warnings.empty());
  const Model model = builder.finalize();
  EXPECT_EQ(model.friction_rule, FrictionRule::Mujoco);
  mjModel* m = load_mujoco_model(path);
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  ASSERT_EQ(d->ncon, 4);
  auto shape_of = [&](int geom) {
    const int body = import.body_map[m->geom_bodyid[geom]];
    for (int s = 0; s < model.shape_count; ++s)
      if (model.shape_body[s] == body) return s;
    return -1;
  };
  std::set<Scalar> seen;
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& contact = d->contact[c];
    const Scalar mujoco = contact.dim == 1 ? 0 : contact.friction[0];
    EXPECT_EQ(contact_friction(model, shape_of(contact.geom1), shape_of(contact.geom2)), mujoco) << "contact " << c;
    seen.insert(mujoco);
  }
  EXPECT_EQ(seen, (std::set<Scalar>{0, 0.2, 0.5, 0.9}));  // the four cases, each as MuJoCo has it
  mj_deleteData(d);
  mj_deleteModel(m);
  std::filesystem::remove(path);
  // the builder's default: the geometric mean, and a condim it does not know is an error
  ModelBuilder own;
  ShapeOptions quarter, one;
  quarter.mu = 0.25, one.mu = 1;
  const int a = own.add_shape_sphere(own.add_body(RigidBody::from_sphere(1, 0.1)), 0.1, quarter);
  const int b = own.add_shape_sphere(own.add_body(RigidBody::from_sphere(1, 0.1)), 0.1, one);
  EXPECT_EQ(contact_friction(own.finalize(), a, b), 0.5);
  ShapeOptions options;
  options.condim = 2;
  EXPECT_NOVAPHY_ERROR(own.add_shape_sphere(own.add_body(RigidBody::from_sphere(1, 0.1)), 0.1, options),
                       "condim must be 1, 3, 4 or 6, got 2");
}

}  // namespace
}  // namespace novaphy
