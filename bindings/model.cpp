// Model, State and Control: every field of the engine's field tables as a numpy view over the
// engine's buffer (no copy). Model views are read-only; State and Control views are writable.
#include "engine/model.h"

#include "bindings/bindings.h"

namespace novaphy::python {

namespace {

template <typename Owner, typename T>
py::array field_view(py::object self, std::vector<T> Owner::*field, int width, bool writeable) {
  Owner& owner = self.cast<Owner&>();
  std::vector<T>& data = owner.*field;
  return view(data.data(), static_cast<int>(data.size() / width), width, self, writeable);
}

template <typename Class>
void bind_counts(Class& c) {
  c.def_readonly("world_count", &ModelCounts::world_count)
      .def_readonly("body_count", &ModelCounts::body_count)
      .def_readonly("joint_count", &ModelCounts::joint_count)
      .def_readonly("joint_coord_count", &ModelCounts::joint_coord_count)
      .def_readonly("joint_dof_count", &ModelCounts::joint_dof_count)
      .def_readonly("articulation_count", &ModelCounts::articulation_count)
      .def_readonly("shape_count", &ModelCounts::shape_count)
      .def_readonly("actuator_count", &ModelCounts::actuator_count);
}

}  // namespace

void bind_model(py::module_& m) {
  py::enum_<JointType>(m, "JointType", "Joint types of the reduced-coordinate solver.")
      .value("Revolute", JointType::Revolute)
      .value("Prismatic", JointType::Prismatic)
      .value("Slide", JointType::Prismatic)
      .value("Ball", JointType::Ball)
      .value("Fixed", JointType::Fixed)
      .value("Free", JointType::Free);

  py::enum_<ShapeType>(m, "ShapeType", "Collision shape types.")
      .value("Plane", ShapeType::Plane)
      .value("Sphere", ShapeType::Sphere)
      .value("Box", ShapeType::Box)
      .value("Capsule", ShapeType::Capsule);

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

#define NOVAPHY_BIND_FIELD(Owner, T, name, width, writeable) \
  .def_property_readonly(#name, [](py::object self) { return field_view(self, &Owner::name, width, writeable); })

  // State and Control first: Model's methods return them
  auto state =
      py::class_<State>(m, "State", "Mutable state: joint and body arrays, numpy views over the engine's buffers.");
  bind_counts(state);
#define NOVAPHY_BIND_STATE_FIELD(T, name, count, width) state NOVAPHY_BIND_FIELD(State, T, name, width, true);
  NOVAPHY_STATE_FIELDS(NOVAPHY_BIND_STATE_FIELD)

  auto control =
      py::class_<Control>(m, "Control", "Control inputs: joint_f generalised forces, actuator_ctrl motor commands.");
  bind_counts(control);
#define NOVAPHY_BIND_CONTROL_FIELD(T, name, count, width) control NOVAPHY_BIND_FIELD(Control, T, name, width, true);
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_BIND_CONTROL_FIELD)

  auto model = py::class_<Model>(m, "Model", "Read-only model: topology and parameters as flat arrays.");
  bind_counts(model);
  model.def_property_readonly("gravity", [](const Model& self) { return self.gravity; })
      .def_readonly("body_name", &Model::body_name)
      .def_readonly("joint_name", &Model::joint_name)
      .def_readonly("actuator_name", &Model::actuator_name)
      .def("state", &Model::state, "A state at the initial coordinates joint_q0, with body_q/body_qd from FK.")
      .def("control", &Model::control, "A zeroed control.");
#define NOVAPHY_BIND_MODEL_FIELD(T, name, count, width) model NOVAPHY_BIND_FIELD(Model, T, name, width, false);
  NOVAPHY_MODEL_FIELDS(NOVAPHY_BIND_MODEL_FIELD)
}

}  // namespace novaphy::python
