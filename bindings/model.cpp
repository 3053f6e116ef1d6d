// Model, State and Control: every field of the engine's field tables as a numpy view over the
// engine's buffer (no copy). Model views are read-only; State and Control views are writable.
#include "engine/model/model.h"

#include <functional>
#include <optional>
#include <variant>

#include "bindings/bindings.h"

namespace novaphy::python {

namespace {

template <typename Owner, typename T>
py::array field_view(py::object self, std::vector<T> Owner::*field, int width, bool writeable) {
  Owner& owner = self.cast<Owner&>();
  std::vector<T>& data = owner.*field;
  // (a width of 0, the keyframes' commands of a model without actuators, makes an empty view)
  return view(data.data(), width > 0 ? static_cast<int>(data.size() / width) : 0, width, self, writeable);
}

// a State's or Control's field as Python holds it: the float32 array of a float32 model's, else the field
template <typename Owner, typename T, typename Float32>
py::array held_view(py::object self, std::vector<T> Owner::*field, std::vector<Float32Of<T>> Float32::*single,
                    int width) {
  Owner& owner = self.cast<Owner&>();
  if (owner.precision == Precision::Float64) return field_view(self, field, width, true);
  std::vector<Float32Of<T>>& data = owner.float32.*single;
  return view(data.data(), width > 0 ? static_cast<int>(data.size() / width) : 0, width, self, true);
}

// to_numpy / from_numpy of a State or Control: its fields as Python holds them, by name
struct Checkpoint {
  std::vector<const char*> fields;

  py::dict to_numpy(const py::object& self) const {
    py::dict out;
    for (const char* name : fields) out[name] = self.attr(name).attr("copy")();
    return out;
  }

  void from_numpy(const py::object& self, const py::dict& arrays) const {
    // check everything first: on error nothing is written
    std::vector<std::pair<py::array, py::array>> writes;
    for (const auto& [key, value] : arrays) {
      const std::string name = py::str(key);
      if (std::find_if(fields.begin(), fields.end(), [&](const char* f) { return name == f; }) == fields.end())
        throw py::value_error("from_numpy: unknown field '" + name + "'");
      const py::array array = py::array::ensure(value);
      if (!array || !(array.dtype().kind() == 'f' || array.dtype().kind() == 'i' || array.dtype().kind() == 'u'))
        throw py::type_error("from_numpy: field '" + name + "' must be a numeric array, got " +
                             (array ? "an array of dtype " + py::str(array.dtype()).cast<std::string>()
                                    : py::str(py::type::of(value)).cast<std::string>()));
      const py::array field = self.attr(name.c_str());
      const std::vector<py::ssize_t> shape(array.shape(), array.shape() + array.ndim());
      const std::vector<py::ssize_t> expected(field.shape(), field.shape() + field.ndim());
      if (shape != expected)
        throw py::value_error("from_numpy: field '" + name + "' has shape " +
                              py::str(py::tuple(py::cast(shape))).cast<std::string>() + ", expected " +
                              py::str(py::tuple(py::cast(expected))).cast<std::string>());
      writes.emplace_back(field, array);
    }
    for (const auto& [field, array] : writes) field[py::ellipsis()] = array;
  }
};

template <typename Owner, typename Class>
void bind_checkpoint(Class& c, const Checkpoint& checkpoint) {
  c.def(
       "copy", [](const Owner& self) { return Owner(self); }, "An independent copy.")
      .def("assign", &Owner::assign, py::arg("other"), "Copies every array of other (same model).")
      .def(
          "to_numpy", [checkpoint](const py::object& self) { return checkpoint.to_numpy(self); },
          "Every array as a dict of numpy copies (a checkpoint).")
      .def(
          "from_numpy",
          [checkpoint](const py::object& self, const py::dict& arrays) { checkpoint.from_numpy(self, arrays); },
          py::arg("arrays"), "Restores arrays from a dict like to_numpy's; checks names and shapes first.");
}

template <typename Class>
void bind_counts(Class& c) {
  c.def_readonly("model_id", &ModelCounts::model_id, "The model this was made by: one number per model.")
      .def_readonly("world_count", &ModelCounts::world_count)
      .def_readonly("body_count", &ModelCounts::body_count)
      .def_readonly("joint_count", &ModelCounts::joint_count)
      .def_readonly("joint_coord_count", &ModelCounts::joint_coord_count)
      .def_readonly("joint_dof_count", &ModelCounts::joint_dof_count)
      .def_readonly("articulation_count", &ModelCounts::articulation_count)
      .def_readonly("shape_count", &ModelCounts::shape_count)
      .def_readonly("actuator_count", &ModelCounts::actuator_count)
      .def_readonly("tendon_count", &ModelCounts::tendon_count)
      .def_readonly("tendon_path_count", &ModelCounts::tendon_path_count)
      .def_readonly("equality_count", &ModelCounts::equality_count)
      .def_readonly("fluid_ellipsoid_count", &ModelCounts::fluid_ellipsoid_count)
      .def_readonly("sensor_count", &ModelCounts::sensor_count)
      .def_readonly("sensor_value_count", &ModelCounts::sensor_value_count,
                    "The sensors' values together (State.sensor_data's length).");
}

// the worlds a call names: a bool mask of world_count entries or world ids (an IndexError names an id out of
// range)
std::vector<int> world_ids(const Model& self, const py::object& given, const char* call) {
  const py::array worlds = py::array::ensure(given);
  if (!worlds)
    throw py::type_error(std::string(call) + ": worlds must be a bool mask or world ids, got " +
                         py::str(py::type::of(given)).cast<std::string>());
  std::vector<int> ids;
  if (worlds.dtype().kind() == 'b') {
    if (worlds.ndim() != 1 || worlds.shape(0) != self.world_count)
      throw py::value_error(
          std::string(call) + ": the mask has shape " +
          py::str(py::tuple(py::cast(std::vector<py::ssize_t>(worlds.shape(), worlds.shape() + worlds.ndim()))))
              .cast<std::string>() +
          ", the model has " + std::to_string(self.world_count) + " worlds");
    const auto mask = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(worlds);
    for (int w = 0; w < self.world_count; ++w)
      if (mask.data()[w]) ids.push_back(w);
  } else if (worlds.dtype().kind() == 'i' || worlds.dtype().kind() == 'u') {
    if (worlds.ndim() > 1) throw py::value_error(std::string(call) + ": world ids must be a 1-d array");
    const auto ids_given = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(worlds);
    for (py::ssize_t i = 0; i < ids_given.size(); ++i) {
      const std::int64_t w = ids_given.data()[i];
      if (w < 0 || w >= self.world_count)
        throw py::index_error(std::string(call) + ": worlds[" + std::to_string(i) + "] = " + std::to_string(w) +
                              " is not a world of the model (0 .. " + std::to_string(self.world_count - 1) + ")");
      ids.push_back(static_cast<int>(w));
    }
  } else {
    throw py::type_error(std::string(call) + ": worlds must be a bool mask or world ids, got an array of dtype " +
                         py::str(worlds.dtype()).cast<std::string>());
  }
  return ids;
}

}  // namespace

void bind_model(py::module_& m) {
  py::enum_<JointType>(m, "JointType", "Joint types of the reduced-coordinate solver.")
      .value("Revolute", JointType::Revolute)
      .value("Prismatic", JointType::Prismatic)
      .value("Slide", JointType::Prismatic)
      .value("Ball", JointType::Ball)
      .value("Fixed", JointType::Fixed)
      .value("Free", JointType::Free)
      .value("Distance", JointType::Distance)
      .value("D6", JointType::D6)
      .value("Cable", JointType::Cable);

  py::enum_<TendonPathKind>(m, "TendonPathKind",
                            "An element of a spatial tendon's path: a site, a sphere or cylinder it wraps around, "
                            "the side site of the wrap before it, a pulley.")
      .value("Site", TendonPathKind::Site)
      .value("Sphere", TendonPathKind::Sphere)
      .value("Cylinder", TendonPathKind::Cylinder)
      .value("SideSite", TendonPathKind::SideSite)
      .value("Pulley", TendonPathKind::Pulley);

  py::enum_<Precision>(m, "Precision",
                       "The precision the solver's batched kernels step a model in; a Float32 model's State and "
                       "Control arrays are float32 (its Model arrays stay float64).")
      .value("Float64", Precision::Float64)
      .value("Float32", Precision::Float32);

  py::enum_<CollisionFilter>(m, "CollisionFilter",
                             "Which shape pairs may collide: GroupAndMask needs (group_a & mask_b) and (group_b & "
                             "mask_a); Mujoco (contype/conaffinity) needs either.")
      .value("GroupAndMask", CollisionFilter::GroupAndMask)
      .value("Mujoco", CollisionFilter::Mujoco);

  py::enum_<FrictionRule>(m, "FrictionRule",
                          "How a contact combines its shapes' friction: GeometricMean sqrt(mu_a mu_b); Mujoco: the "
                          "shape of higher priority decides, else the larger mu; condim 1: frictionless.")
      .value("GeometricMean", FrictionRule::GeometricMean)
      .value("Mujoco", FrictionRule::Mujoco);

  py::enum_<ShapeType>(m, "ShapeType", "Collision shape types.")
      .value("Plane", ShapeType::Plane)
      .value("Sphere", ShapeType::Sphere)
      .value("Box", ShapeType::Box)
      .value("Capsule", ShapeType::Capsule)
      .value("Cylinder", ShapeType::Cylinder)
      .value("Ellipsoid", ShapeType::Ellipsoid)
      .value("Mesh", ShapeType::Mesh);

  auto sensor_type =
      py::enum_<SensorType>(m, "SensorType",
                            "What a sensor measures (MuJoCo's sensor of the same name, lower case, where MJCF has one; "
                            "ModelBuilder.add_sensor).");
  for (int t = 0; t < kSensorTypeCount; ++t)
    sensor_type.value(sensor_type_label(static_cast<SensorType>(t)), static_cast<SensorType>(t));
  sensor_type.def_property_readonly(
      "mjcf_name", [](SensorType type) { return sensor_type_name(type); },
      "The type's name as MJCF writes it ('gyro'), or NovaPhy's for its own types.");

  py::class_<Transform>(m, "Transform", "Rigid transform: position and rotation quaternion [x, y, z, w].")
      .def(py::init([](const Vec3& position, const Eigen::Vector4d& rotation) {
             Transform t;
             t.p = position;
             t.q.coeffs() = rotation;
             return t;
           }),
           py::arg("position") = Vec3::Zero(), py::arg("rotation") = Eigen::Vector4d(0, 0, 0, 1))
      .def_property(
          "position", [](const Transform& t) { return t.p; }, [](Transform& t, const Vec3& p) { t.p = p; })
      .def_property(
          "rotation", [](const Transform& t) { return Eigen::Vector4d(t.q.coeffs()); },
          [](Transform& t, const Eigen::Vector4d& q) { t.q.coeffs() = q; })
      .def("__mul__", &Transform::operator*)
      .def("inverse", &Transform::inverse)
      .def("__repr__", [](const Transform& t) {
        return py::str("Transform(position={}, rotation={})")
            .format(py::cast(Eigen::RowVector3d(t.p)), py::cast(Eigen::RowVector4d(t.q.coeffs())));
      });

// (a width may name the owner's counts: the keyframes' rows are a coordinate, dof or actuator each)
#define NOVAPHY_BIND_FIELD(Owner, T, name, width, writeable)                                                           \
  .def_property_readonly(#name, [](py::object self) {                                                                  \
    const ModelCounts& counts = self.cast<const Owner&>();                                                             \
    [[maybe_unused]] const int joint_coord_count = counts.joint_coord_count, joint_dof_count = counts.joint_dof_count, \
                               actuator_count = counts.actuator_count;                                                 \
    return field_view(self, &Owner::name, width, writeable);                                                           \
  })

  // State and Control first: Model's methods return them
  auto state = py::class_<State>(m, "State",
                                 "Mutable state: joint and body arrays, numpy views over the engine's buffers "
                                 "(float32 in a float32 model).");
  bind_counts(state);
  Checkpoint state_checkpoint;
#define NOVAPHY_BIND_STATE_FIELD(T, name, count, width)                                                  \
  state.def_property_readonly(                                                                           \
      #name, [](py::object self) { return held_view(self, &State::name, &StateFloat32::name, width); }); \
  state_checkpoint.fields.push_back(#name);
  NOVAPHY_STATE_FIELDS(NOVAPHY_BIND_STATE_FIELD)
  bind_checkpoint<State>(state, state_checkpoint);

  auto control = py::class_<Control>(m, "Control",
                                     "Control inputs: joint_f generalised forces, actuator_ctrl motor commands "
                                     "(float32 in a float32 model).");
  bind_counts(control);
  Checkpoint control_checkpoint;
#define NOVAPHY_BIND_CONTROL_FIELD(T, name, count, width)                                                    \
  control.def_property_readonly(                                                                             \
      #name, [](py::object self) { return held_view(self, &Control::name, &ControlFloat32::name, width); }); \
  control_checkpoint.fields.push_back(#name);
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_BIND_CONTROL_FIELD)
  bind_checkpoint<Control>(control, control_checkpoint);

  auto model = py::class_<Model>(m, "Model", "Read-only model: topology and parameters as flat arrays.");
  bind_counts(model);
  model.def_property_readonly("gravity", [](const Model& self) { return self.gravity; })
      .def_readonly("timestep", &Model::timestep,
                    "The step the scene was made for, in s (a file's <option timestep>; 0.002 by default).")
      .def_readonly("precision", &Model::precision, "Precision of the solver's batched kernels for this model.")
      .def_readonly("fluid_density", &Model::fluid_density, "The medium's density, kg/m^3 (ModelBuilder.set_fluid).")
      .def_readonly("fluid_viscosity", &Model::fluid_viscosity, "The medium's viscosity, Pa s.")
      .def_property_readonly(
          "wind", [](const Model& self) { return self.wind; }, "The medium's velocity, m/s (world frame).")
      .def_readonly("body_name", &Model::body_name)
      .def_readonly("shape_name", &Model::shape_name)
      .def_readonly("joint_name", &Model::joint_name)
      .def_readonly("actuator_name", &Model::actuator_name)
      .def_readonly("tendon_name", &Model::tendon_name)
      .def_readonly("equality_name", &Model::equality_name)
      .def_readonly("sensor_name", &Model::sensor_name,
                    "Each sensor's name; its values are State.sensor_data[sensor_start[s]:sensor_start[s + 1]].")
      .def_readonly("collision_filter", &Model::collision_filter, "The rule shape_collision_group/_mask filter by.")
      .def_readonly("friction_rule", &Model::friction_rule, "How contacts combine their shapes' friction.")
      .def_readonly("keyframes", &Model::keyframe_name, "The keyframes' names (rows of keyframe_q, _qd, _ctrl).")
      .def(
          "state",
          [](const Model& self, std::optional<std::string> keyframe) {
            return keyframe ? self.state(*keyframe) : self.state();
          },
          py::kw_only(), py::arg("keyframe") = py::none(),
          "A state at the initial coordinates joint_q0, or at the named keyframe's coordinates and velocities, with "
          "body_q/body_qd from FK.")
      .def(
          "control",
          [](const Model& self, std::optional<std::string> keyframe) {
            return keyframe ? self.control(*keyframe) : self.control();
          },
          py::kw_only(), py::arg("keyframe") = py::none(),
          "A zeroed control with the model's PD gains, or with the named keyframe's actuator commands.")
      .def(
          "reset_worlds",
          [](const Model& self, State& state, const py::object& given, const py::object& keyframe, int threads) {
            const std::vector<int> ids = world_ids(self, given, "reset_worlds");
            int k = -1;
            if (py::isinstance<py::str>(keyframe))
              k = self.keyframe(keyframe.cast<std::string>());
            else if (!keyframe.is_none())
              k = keyframe.cast<int>();
            const py::gil_scoped_release release;
            const Widened<State> written(state, true, threads);
            self.reset_worlds(state, ids, k, threads);
          },
          py::arg("state"), py::arg("worlds"), py::arg("keyframe") = py::none(), py::kw_only(), py::arg("threads") = 0,
          "Worlds of `state` (a bool mask of world_count entries, or world ids) back to joint_q0 at rest, or to the "
          "keyframe (a name or an index): their joint_q, joint_qd, body_f (zero), body_q and body_qd (FK), and "
          "world_reset set, so that the next collide and step use none of their history (warm starts, a kept "
          "factor). Every other world is left as it was.")
      .def(
          "restart_worlds",
          [](const Model& self, State& state, const py::object& given, int threads) {
            const std::vector<int> ids = world_ids(self, given, "restart_worlds");
            const py::gil_scoped_release release;
            const Widened<State> written(state, true, threads);
            self.restart_worlds(state, ids, threads);
          },
          py::arg("state"), py::arg("worlds"), py::kw_only(), py::arg("threads") = 0,
          "Worlds of `state` (a bool mask or world ids) start afresh from the joint_q and joint_qd written into them "
          "(a start of the caller's own): as reset_worlds, with those coordinates and velocities kept and each Free "
          "or Ball quaternion normalised. Refuses a value that is not finite or a zero quaternion, naming it.")
      .def(
          "set_parameter",
          [](Model& self, const std::string& field, const py::object& values, const py::object& worlds) {
            std::vector<int> ids;
            if (worlds.is_none())
              for (int w = 0; w < self.world_count; ++w) ids.push_back(w);
            else
              ids = world_ids(self, worlds, ("set_parameter " + field).c_str());
            const auto given = py::array_t<Scalar, py::array::c_style | py::array::forcecast>::ensure(values);
            if (!given)
              throw py::type_error("set_parameter " + field + ": values must be numbers, got " +
                                   py::str(py::type::of(values)).cast<std::string>());
            self.set_parameter(field, ids, given.data(), static_cast<size_t>(given.size()));
          },
          py::arg("field"), py::arg("values"), py::arg("worlds") = py::none(),
          "Field `field` (one of Model.parameter_names) of some worlds (a bool mask or world ids; None: every "
          "world) from `values`: each world's bodies, dofs, shapes (static ones aside) or actuators in the model's "
          "order, or its own entry for world_gravity, world after world, as world_view(model, model.<field>)[worlds] "
          "lays them out. Every value is checked before any is written (ValueError naming the world and item); a "
          "solver reads the new values at its next step.")
      .def_property_readonly_static(
          "parameter_names", [](const py::object&) { return Model::parameter_names(); },
          "The fields set_parameter writes: what may change per world after finalize.");
#define NOVAPHY_BIND_MODEL_FIELD(T, name, count, width) model NOVAPHY_BIND_FIELD(Model, T, name, width, false);
  NOVAPHY_MODEL_FIELDS(NOVAPHY_BIND_MODEL_FIELD)

  // per class, each field's rows as its field table counts them ("body_count", "joint_count + 1"): which arrays
  // split into worlds (novaphy.world_view)
  py::dict field_rows, model_rows, state_rows, control_rows;
#define NOVAPHY_FIELD_ROWS(rows, T, name, count, width) rows[#name] = #count;
#define NOVAPHY_MODEL_ROWS(T, name, count, width) NOVAPHY_FIELD_ROWS(model_rows, T, name, count, width)
#define NOVAPHY_STATE_ROWS(T, name, count, width) NOVAPHY_FIELD_ROWS(state_rows, T, name, count, width)
#define NOVAPHY_CONTROL_ROWS(T, name, count, width) NOVAPHY_FIELD_ROWS(control_rows, T, name, count, width)
  NOVAPHY_MODEL_FIELDS(NOVAPHY_MODEL_ROWS)
  NOVAPHY_STATE_FIELDS(NOVAPHY_STATE_ROWS)
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_CONTROL_ROWS)
  field_rows["Model"] = model_rows, field_rows["State"] = state_rows, field_rows["Control"] = control_rows;
  m.attr("_field_rows") = field_rows;
}

}  // namespace novaphy::python
