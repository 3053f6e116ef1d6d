// ModelBuilder's sensors (model.h's SensorType): checked when added, laid out world after world's as added.
#include <algorithm>

#include "engine/model/builder.h"
#include "engine/model/builder_checks.h"

namespace novaphy {

int ModelBuilder::add_sensor(SensorType type, int object, const SensorOptions& options) {
  const std::string item = label("sensor", sensor_count(), options.name);
  const int t = static_cast<int>(type);
  if (t < 0 || t >= kSensorTypeCount)
    fail(item, ": type ", t, " is not a SensorType (0 .. ", kSensorTypeCount - 1, ")");
  const std::string kind = std::string(sensor_type_name(type)) + " sensor";
  switch (sensor_object_kind(type)) {
    case SensorObject::Joint: {
      if (object < 0 || object >= joint_count())
        fail(item, ": joint index ", object, " out of range [0, ", joint_count(), ")");
      const bool ball = type == SensorType::BallQuat || type == SensorType::BallAngVel;
      if (ball && joints_[object].type != JointType::Ball)
        fail(item, ": a ", kind, " reads a Ball joint; joint ", object, " is ", joint_type_name(joints_[object].type));
      if (!ball) check_scalar_joint(item, "a " + kind + " reads a Revolute or Prismatic joint", object);
      break;
    }
    case SensorObject::Tendon:
      if (object < 0 || object >= tendon_count())
        fail(item, ": tendon index ", object, " out of range [0, ", tendon_count(), ")");
      break;
    case SensorObject::Body:
      if (object < -1 || object >= body_count())
        fail(item, ": body index ", object, " out of range [-1, ", body_count(), ")");
      break;
  }
  SensorOptions o = options;
  o.xform = checked_transform(item, "xform", options.xform);
  check_nonnegative(item, "cutoff", options.cutoff);
  const ShapeType zone = static_cast<ShapeType>(options.zone_type);
  if (options.zone_type != -1) {
    if (type != SensorType::Touch) fail(item, ": only a touch sensor has a zone, this is a ", kind);
    if (zone != ShapeType::Sphere && zone != ShapeType::Box && zone != ShapeType::Ellipsoid &&
        zone != ShapeType::Capsule && zone != ShapeType::Cylinder)
      fail(item, ": zone_type ", options.zone_type,
           " is not -1 (the whole body), Sphere, Box, Ellipsoid, Capsule or Cylinder");
    const int sizes = zone == ShapeType::Sphere ? 1 : zone == ShapeType::Box || zone == ShapeType::Ellipsoid ? 3 : 2;
    for (int k = 0; k < sizes; ++k) check_positive(item, "zone_size", options.zone_size[k]);
  }
  if ((type == SensorType::Touch || type == SensorType::ContactForce || type == SensorType::SubtreeCom) && object < 0)
    fail(item, ": a ", kind, " needs a body, not the world (-1)");
  if (options.shape != -1) {
    if (type != SensorType::Touch && type != SensorType::ContactForce)
      fail(item, ": only a touch or contactforce sensor reads one shape's contacts, this is a ", kind);
    if (options.shape < 0 || options.shape >= shape_count())
      fail(item, ": shape index ", options.shape, " out of range [0, ", shape_count(), ")");
    if (shapes_[options.shape].body != object)
      fail(item, ": shape ", options.shape, " is not a shape of body ", object, " (its body is ",
           shapes_[options.shape].body, ")");
  }
  // the world of its object (a sensor of the world: world 0 of this builder; add_builder places it)
  int world = 0;
  switch (sensor_object_kind(type)) {
    case SensorObject::Joint: world = body_world_[joints_[object].child]; break;
    case SensorObject::Tendon: world = tendon_world(object); break;
    case SensorObject::Body: world = object >= 0 ? body_world_[object] : 0; break;
  }
  sensors_.push_back({type, object, o, world});
  return sensor_count() - 1;
}

void ModelBuilder::lay_out_sensors(Model& model) const {
  // each world's sensors together, in the order added (a replicated world's as in its builder)
  std::vector<int> order(sensors_.size());
  for (size_t s = 0; s < order.size(); ++s) order[s] = static_cast<int>(s);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return sensors_[a].world < sensors_[b].world; });
  model.sensor_count = sensor_count();
  model.sensor_start.assign(1, 0);
  for (const int s : order) {
    const SensorRecord& r = sensors_[s];
    model.sensor_type.push_back(static_cast<int>(r.type));
    model.sensor_object.push_back(r.object);
    model.sensor_frame.resize(model.sensor_frame.size() + 7);
    r.options.xform.to_array(&model.sensor_frame[model.sensor_frame.size() - 7]);
    model.sensor_zone.insert(model.sensor_zone.end(), {static_cast<Scalar>(r.options.zone_type), r.options.zone_size[0],
                                                       r.options.zone_size[1], r.options.zone_size[2]});
    model.sensor_cutoff.push_back(r.options.cutoff);
    model.sensor_shape.push_back(r.options.shape);
    model.sensor_world.push_back(r.world);
    model.sensor_start.push_back(model.sensor_start.back() + sensor_dim(r.type));
    model.sensor_name.push_back(r.options.name);
  }
  model.sensor_value_count = model.sensor_start.back();
}

}  // namespace novaphy
