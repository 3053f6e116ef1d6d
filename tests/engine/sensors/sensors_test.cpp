#include "engine/sensors/sensors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>

#include "engine/import/mjcf_import.h"
#include "engine/sensors/zone.h"
#include "engine/solver/solver_featherstone.h"
#include "test_support_errors.h"

namespace novaphy {
namespace {

const char* const kSensorsXml = NOVAPHY_TEST_MODEL_DIR "/sensors.xml";

using MjModelPtr = std::unique_ptr<mjModel, void (*)(mjModel*)>;
using MjDataPtr = std::unique_ptr<mjData, void (*)(mjData*)>;

// the largest difference of each imported sensor's values from MuJoCo's sensordata after `steps` mj_steps, both
// engines stepping from keyframe `key` (a quaternion compared up to its sign), relative to max(1, |MuJoCo's|)
Scalar largest_sensor_difference(int key, int steps, Precision precision = Precision::Float64) {
  const MjModelPtr m(load_mujoco_model(kSensorsXml), mj_deleteModel);
  const MjDataPtr d(mj_makeData(m.get()), mj_deleteData);
  ModelBuilder builder;
  builder.set_precision(precision);
  const MujocoImport imported = import_mujoco_model(builder, m.get());
  const Model model = builder.finalize();
  EXPECT_EQ(model.sensor_count, m->nsensor - 1);  // all but the magnetometer
  mj_resetDataKeyframe(m.get(), d.get(), key);
  State state = model.state(model.keyframe_name[key]);
  Control control = model.control();
  SolverFeatherstoneSettings settings;
  settings.angular_damping = 0;
  SolverFeatherstone solver(model, settings);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  for (int k = 0; k < steps; ++k) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, m->opt.timestep);
    mj_step(m.get(), d.get());
  }
  Scalar worst = 0;
  for (int i = 0; i < m->nsensor; ++i) {
    const int s = imported.sensor_map[i];
    if (s < 0) {
      EXPECT_EQ(m->sensor_type[i], mjSENS_MAGNETOMETER);
      continue;
    }
    const int dim = m->sensor_dim[i];
    EXPECT_EQ(model.sensor_start[s + 1] - model.sensor_start[s], dim) << model.sensor_name[s];
    const bool quaternion = m->sensor_type[i] == mjSENS_FRAMEQUAT || m->sensor_type[i] == mjSENS_BALLQUAT;
    Scalar same = 0, flipped = 0, scale = 1;
    for (int k = 0; k < dim; ++k) {
      const Scalar ours = state.sensor_data[model.sensor_start[s] + k], theirs = d->sensordata[m->sensor_adr[i] + k];
      same = std::max(same, std::abs(ours - theirs));
      flipped = std::max(flipped, std::abs(ours + theirs));
      scale = std::max(scale, std::abs(theirs));
    }
    const Scalar difference = (quaternion ? std::min(same, flipped) : same) / scale;
    EXPECT_LT(difference, precision == Precision::Float64 ? 1e-9 : 1e-3)
        << "sensor " << i << " ('" << model.sensor_name[s] << "', "
        << sensor_type_name(SensorType(model.sensor_type[s])) << ") after " << steps << " steps";
    worst = std::max(worst, difference);
  }
  return worst;
}

TEST(Sensors, MatchMujocoAfterOneStep) {
  // positions, velocities, accelerations, forces and torques of a swinging chain with hinge, slide and ball joints
  EXPECT_LT(largest_sensor_difference(0, 1), 1e-9);
  EXPECT_LT(largest_sensor_difference(0, 1, Precision::Float32), 1e-3);
}

TEST(Sensors, TouchOfARestingBallIsItsWeightAsInMujoco) {
  // after 0.4 s the ball rests on the floor: its touch sensors (the zone holding the contact, and the one under the
  // floor that the contact's ray meets) read its weight, the one beside it nothing, as in MuJoCo
  EXPECT_LT(largest_sensor_difference(1, 200), 1e-9);
}

// sensors.xml from its keyframe "resting", with `extra` sensors added (given the ball's body), stepped 0.4 s: the
// ball rests on the floor
struct RestingBall {
  explicit RestingBall(const std::function<void(ModelBuilder&, int)>& extra = {}) {
    ModelBuilder builder;
    ball = import_mjcf(builder, kSensorsXml).body_map[4];
    if (extra) extra(builder, ball);
    model = builder.finalize();
    state = model.state("resting");
    SolverFeatherstone solver(model);
    CollisionPipeline pipeline(model);
    contacts = pipeline.contacts();
    const Control control = model.control();
    for (int k = 0; k < 200; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, control, contacts, model.timestep);
    }
  }
  int ball = -1;
  Model model;
  State state;
  Contacts contacts;
};

// the index of the shape called `name` in what `builder` holds so far
int shape_named(const ModelBuilder& builder, const std::string& name) {
  const Model model = builder.finalize();
  for (int s = 0; s < model.shape_count; ++s)
    if (model.shape_name[s] == name) return s;
  ADD_FAILURE() << "no shape " << name;
  return -1;
}

TEST(Sensors, ContactForceAndProjectedGravity) {
  // NovaPhy's own sensors on the resting ball: the floor's push on it (on the body, on the geom that touches the
  // floor, on the one that does not), and gravity seen from a frame turned a quarter turn about x (R^T (0, 0, -1) =
  // (0, -1, 0))
  SensorOptions turned;
  turned.xform.q = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()));
  int force = -1, gravity = -1, touching = -1, antenna = -1;
  const RestingBall scene([&](ModelBuilder& builder, int ball) {
    SensorOptions on_geom, on_antenna;
    on_geom.shape = shape_named(builder, "ballgeom");
    on_antenna.shape = shape_named(builder, "antenna");
    force = builder.add_sensor(SensorType::ContactForce, ball);
    gravity = builder.add_sensor(SensorType::ProjectedGravity, ball, turned);
    touching = builder.add_sensor(SensorType::ContactForce, ball, on_geom);
    antenna = builder.add_sensor(SensorType::Touch, ball, on_antenna);
  });
  const Model& model = scene.model;
  const Scalar weight = -model.gravity.z() * model.body_mass[scene.ball];
  const Scalar* f = &scene.state.sensor_data[model.sensor_start[force]];
  EXPECT_NEAR(f[0], 0, 1e-6 * weight);
  EXPECT_NEAR(f[1], 0, 1e-6 * weight);
  EXPECT_NEAR(f[2], weight, 1e-6 * weight);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(scene.state.sensor_data[model.sensor_start[touching] + k], f[k]);
  EXPECT_EQ(scene.state.sensor_data[model.sensor_start[antenna]], 0);
  const Scalar* g = &scene.state.sensor_data[model.sensor_start[gravity]];
  const Vec3 expected(0, -1, 0);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(g[k], expected[k], 1e-9) << k;
}

TEST(Sensors, EachWorldAsAloneAndTheSameOnAnyThreads) {
  ModelBuilder robot;
  robot.add_mjcf(kSensorsXml);
  const Model alone = robot.finalize();
  ModelBuilder batch;
  batch.replicate(robot, 3);  // in one place: worlds never touch, and each is bit for bit as alone
  const Model model = batch.finalize();
  ASSERT_EQ(model.sensor_value_count, 3 * alone.sensor_value_count);
  for (int w = 0; w < 3; ++w)
    for (int s = 0; s < alone.sensor_count; ++s) EXPECT_EQ(model.sensor_world[w * alone.sensor_count + s], w);
  // world w from keyframe w % 2, stepped alone and in the batch on one and on two threads
  const auto run = [](const Model& m, const std::vector<int>& keys, int threads) {
    State state = m.state();
    for (size_t w = 0; w < keys.size(); ++w) m.reset_worlds(state, {static_cast<int>(w)}, keys[w]);
    SolverFeatherstoneSettings settings;
    settings.num_threads = threads;
    SolverFeatherstone solver(m, settings);
    CollisionPipeline pipeline(m);
    Contacts contacts = pipeline.contacts();
    for (int k = 0; k < 20; ++k) {
      pipeline.collide(state, contacts);
      solver.step(state, state, m.control(), contacts, m.timestep);
    }
    return state.sensor_data;
  };
  const std::vector<Scalar> one = run(model, {0, 1, 0}, 1), two = run(model, {0, 1, 0}, 2);
  EXPECT_EQ(one, two);
  const std::vector<Scalar> moving = run(alone, {0}, 1), resting = run(alone, {1}, 1);
  const int n = alone.sensor_value_count;
  for (int w = 0; w < 3; ++w) {
    const std::vector<Scalar>& own = w == 1 ? resting : moving;
    for (int k = 0; k < n; ++k) EXPECT_EQ(one[w * n + k], own[k]) << "world " << w << " value " << k;
  }
}

TEST(Sensors, TheSameWhetherTheStepWritesAnotherStateOrItsOwn) {
  ModelBuilder builder;
  builder.add_mjcf(kSensorsXml);
  const Model model = builder.finalize();
  State in_place = model.state("moving"), from = model.state("moving"), to = model.state();
  SolverFeatherstone a(model), b(model);
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  pipeline.collide(in_place, contacts);
  a.step(in_place, in_place, model.control(), contacts, model.timestep);
  pipeline.collide(from, contacts);
  b.step(from, to, model.control(), contacts, model.timestep);
  EXPECT_EQ(to.sensor_data, in_place.sensor_data);
  EXPECT_NE(to.sensor_data, std::vector<Scalar>(to.sensor_data.size(), 0));
}

TEST(Sensors, ResetWorldsZeroTheirSensors) {
  RestingBall scene;
  State& state = scene.state;
  ASSERT_GT(std::abs(state.sensor_data[0]) + std::abs(state.sensor_data[1]), 0);
  scene.model.reset_worlds(state, {0});
  for (const Scalar x : state.sensor_data) EXPECT_EQ(x, 0);
}

TEST(Sensors, ZoneMetByARayOrHoldingItsOrigin) {
  const Vec3 down(0, 0, -1);
  for (const ShapeType type :
       {ShapeType::Sphere, ShapeType::Box, ShapeType::Ellipsoid, ShapeType::Capsule, ShapeType::Cylinder}) {
    const Vec3 size(0.5, 0.5, 0.5);
    const char* name = shape_type_name(type);
    EXPECT_TRUE(ray_meets_zone(type, size, Vec3::Zero(), down)) << name;                 // inside
    EXPECT_TRUE(ray_meets_zone(type, size, Vec3(0, 0, 2), down)) << name;                // ahead
    EXPECT_FALSE(ray_meets_zone(type, size, Vec3(0, 0, -2), down)) << name;              // behind
    EXPECT_FALSE(ray_meets_zone(type, size, Vec3(2, 0, 2), down)) << name;               // beside
    EXPECT_TRUE(ray_meets_zone(type, size, Vec3(0.3, 0.3, 3), Vec3(0, 0, -2))) << name;  // any length
    EXPECT_FALSE(ray_meets_zone(type, size, Vec3(0, 0, 2), Vec3::Zero())) << name;       // no direction
  }
  // where the shapes differ: a box's corner, a capsule's cap, a cylinder's rim
  EXPECT_TRUE(ray_meets_zone(ShapeType::Box, Vec3(1, 1, 1), Vec3(0.9, 0.9, 5), Vec3(0, 0, -1)));
  EXPECT_FALSE(ray_meets_zone(ShapeType::Sphere, Vec3(1, 1, 1), Vec3(0.9, 0.9, 5), Vec3(0, 0, -1)));
  EXPECT_TRUE(ray_meets_zone(ShapeType::Capsule, Vec3(0.5, 1, 0), Vec3(0, 0, 1.4), Vec3(1, 0, 0)));
  EXPECT_FALSE(ray_meets_zone(ShapeType::Cylinder, Vec3(0.5, 1, 0), Vec3(0, 0, 1.4), Vec3(1, 0, 0)));
  EXPECT_TRUE(ray_meets_zone(ShapeType::Cylinder, Vec3(0.5, 1, 0), Vec3(-2, 0, 0.99), Vec3(1, 0, 0)));
  EXPECT_FALSE(ray_meets_zone(ShapeType::Ellipsoid, Vec3(1, 0.1, 0.1), Vec3(0, 0.5, 2), Vec3(0, 0, -1)));
}

TEST(Sensors, BuilderRefusesBadSensorsByName) {
  ModelBuilder b;
  const int body = b.add_body({1, Vec3::Zero(), Mat3::Identity()});
  const int hinge = b.add_joint_revolute(-1, body);
  const int ball_body = b.add_body({1, Vec3::Zero(), Mat3::Identity()});
  b.add_joint_ball(body, ball_body);
  ASSERT_EQ(ball_body, 1);
  SensorOptions named;
  named.name = "imu";
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::JointPos, 5, named), "sensor 0 ('imu'): joint index 5 out of range");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::BallQuat, hinge), "reads a Ball joint; joint 0 is Revolute");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::JointVel, 1), "reads a Revolute or Prismatic joint");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Gyro, 7), "body index 7 out of range [-1, 2)");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::TendonPos, 0), "tendon index 0 out of range");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Touch, -1), "a touch sensor needs a body, not the world");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(static_cast<SensorType>(99), 0), "type 99 is not a SensorType");
  SensorOptions zone;
  zone.zone_type = static_cast<int>(ShapeType::Box);
  zone.zone_size = Vec3(0.1, -0.1, 0.1);
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Touch, body, zone), "zone_size must be finite and > 0, got -0.1");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Gyro, body, zone), "only a touch sensor has a zone");
  zone.zone_type = static_cast<int>(ShapeType::Mesh);
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Touch, body, zone), "zone_type 6 is not -1");
  SensorOptions shaped;
  shaped.shape = 0;
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Gyro, body, shaped), "only a touch or contactforce sensor reads one");
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Touch, body, shaped), "shape index 0 out of range [0, 0)");
  b.add_shape_sphere(ball_body, 0.1);
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Touch, body, shaped),
                       "shape 0 is not a shape of body 0 (its body is 1)");
  SensorOptions bad;
  bad.cutoff = -1;
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Gyro, body, bad), "cutoff must be finite and >= 0, got -1");
  bad.cutoff = 0;
  bad.xform.p.x() = NAN;
  EXPECT_NOVAPHY_ERROR(b.add_sensor(SensorType::Gyro, body, bad), "xform[0] is not finite");
  EXPECT_EQ(b.sensor_count(), 0);
}

}  // namespace
}  // namespace novaphy
