// RigidBody, JointDofConfig and ModelBuilder with the seed's keyword arguments.
#include "engine/model/builder.h"

#include <cmath>
#include <optional>

#include "bindings/bindings.h"

namespace novaphy::python {

namespace {

// a sensor type given as a SensorType or as its MJCF name
SensorType sensor_type_of(const py::object& type) {
  if (!py::isinstance<py::str>(type)) return type.cast<SensorType>();
  const std::string name = type.cast<std::string>();
  std::string names;
  for (int t = 0; t < kSensorTypeCount; ++t) {
    if (name == sensor_type_name(static_cast<SensorType>(t))) return static_cast<SensorType>(t);
    names += std::string(t ? ", " : "") + sensor_type_name(static_cast<SensorType>(t));
  }
  throw py::value_error("add_sensor: no sensor type '" + name + "' (types: " + names + ")");
}

ActuatorOptions actuator_options(Scalar gear, Scalar ctrl_lower, Scalar ctrl_upper, Scalar force_lower,
                                 Scalar force_upper, const std::string& name, Scalar gain = 1,
                                 const Vec3& bias = Vec3::Zero()) {
  ActuatorOptions a = ActuatorOptions::motor(gear, ctrl_lower, ctrl_upper, force_lower, force_upper, name);
  a.gain = gain;
  a.bias = bias;
  return a;
}

JointDofConfig dof_config(py::object axis) {
  if (axis.is_none()) return {};
  if (py::isinstance<JointDofConfig>(axis)) return axis.cast<JointDofConfig>();
  try {
    JointDofConfig dof;
    dof.axis = axis.cast<Vec3>();
    return dof;
  } catch (const py::cast_error&) {
    throw py::type_error("axis must be a JointDofConfig or a sequence of 3 numbers, got " +
                         py::str(py::type::of(axis)).cast<std::string>());
  }
}

auto joint_adder(JointType type) {
  return [type](ModelBuilder& builder, int parent, int child, std::optional<Transform> parent_xform,
                std::optional<Transform> child_xform, py::object axis, std::optional<Scalar> armature,
                std::optional<Scalar> damping, std::optional<Scalar> frictionloss, std::optional<Scalar> stiffness,
                std::optional<Scalar> limit_lower, std::optional<Scalar> limit_upper, std::optional<Scalar> target_ke,
                std::optional<Scalar> target_kd, const std::string& name) {
    JointOptions options;
    options.parent_xform = parent_xform.value_or(Transform::identity());
    options.child_xform = child_xform.value_or(Transform::identity());
    options.dof = dof_config(axis);
    if (armature) options.dof.armature = *armature;
    if (damping) options.dof.damping = *damping;
    if (frictionloss) options.dof.frictionloss = *frictionloss;
    if (stiffness) options.dof.stiffness = *stiffness;
    if (limit_lower) options.dof.limit_lower = *limit_lower;
    if (limit_upper) options.dof.limit_upper = *limit_upper;
    if (target_ke) options.dof.target_ke = *target_ke;
    if (target_kd) options.dof.target_kd = *target_kd;
    options.name = name;
    return builder.add_joint(type, parent, child, options);
  };
}

template <typename Class>
void def_joint(Class& c, const char* method, JointType type, const char* doc) {
  c.def(method, joint_adder(type), py::arg("parent"), py::arg("child"), py::kw_only(),
        py::arg("parent_xform") = py::none(), py::arg("child_xform") = py::none(), py::arg("axis") = py::none(),
        py::arg("armature") = py::none(), py::arg("damping") = py::none(), py::arg("frictionloss") = py::none(),
        py::arg("stiffness") = py::none(), py::arg("limit_lower") = py::none(), py::arg("limit_upper") = py::none(),
        py::arg("target_ke") = py::none(), py::arg("target_kd") = py::none(), py::arg("name") = "", doc);
}

// a shape's keyword arguments (SHAPE_KWARGS) as the lambdas take them and pass them on
#define SHAPE_PARAMS                                                                                                  \
  Scalar mu, Scalar restitution, int group, int mask, int priority, int condim, Scalar mu_torsion, Scalar mu_rolling, \
      const std::array<Scalar, 2>&solref, const std::array<Scalar, 5>&solimp, Scalar solmix, Scalar margin,           \
      Scalar gap, const std::string &name
#define SHAPE_VALUES \
  mu, restitution, group, mask, priority, condim, mu_torsion, mu_rolling, solref, solimp, solmix, margin, gap, name

ShapeOptions shape_options(std::optional<Transform> xform, SHAPE_PARAMS) {
  ShapeOptions options;
  options.xform = xform.value_or(Transform::identity());
  options.mu = mu;
  options.restitution = restitution;
  options.collision_group = group;
  options.collision_mask = mask;
  options.priority = priority;
  options.condim = condim;
  options.mu_torsion = mu_torsion;
  options.mu_rolling = mu_rolling;
  options.solref = solref;
  options.solimp = solimp;
  options.solmix = solmix;
  options.margin = margin;
  options.gap = gap;
  options.name = name;
  return options;
}

// keyword arguments shared by every add_shape_* and plane
#define XFORM_KWARG py::kw_only(), py::arg("xform") = py::none()
#define SHAPE_KWARGS                                                                                                 \
  py::arg("mu") = 0.5, py::arg("restitution") = 0.0, py::arg("collision_group") = 1, py::arg("collision_mask") = -1, \
  py::arg("priority") = 0, py::arg("condim") = 3, py::arg("mu_torsion") = 0.005, py::arg("mu_rolling") = 0.0001,     \
  py::arg("solref") = std::array<Scalar, 2>{0, 0},                                                                   \
  py::arg("solimp") = std::array<Scalar, 5>{0.9, 0.95, 0.001, 0.5, 2}, py::arg("solmix") = 1.0,                      \
  py::arg("margin") = 0.0, py::arg("gap") = 0.0, py::arg("name") = ""

// runs an importer and passes each of its warnings to Python's warnings module
template <std::vector<std::string> (ModelBuilder::*importer)(const std::string&, const ImportOptions&)>
std::vector<std::string> import_file(ModelBuilder& builder, const std::string& path, std::optional<Transform> xform,
                                     bool static_shapes) {
  ImportOptions options;
  options.xform = xform.value_or(Transform::identity());
  options.static_shapes = static_shapes;
  const std::vector<std::string> warnings = (builder.*importer)(path, options);
  const py::object warn = py::module_::import("warnings").attr("warn");
  for (const std::string& w : warnings) warn("novaphy: " + w, py::handle(PyExc_UserWarning), 2);
  return warnings;
}

}  // namespace

void bind_builder(py::module_& m) {
  py::class_<RigidBody>(m, "RigidBody", "Mass, centre of mass and 3x3 inertia about the centre of mass (body frame).")
      .def(py::init([](Scalar mass, const Vec3& com, const Mat3& inertia) {
             return RigidBody{mass, com, inertia};
           }),
           py::arg("mass") = 1.0, py::arg("com") = Vec3::Zero(), py::arg("inertia") = Mat3::Identity())
      .def_readwrite("mass", &RigidBody::mass)
      .def_readwrite("com", &RigidBody::com)
      .def_readwrite("inertia", &RigidBody::inertia)
      .def_static("from_box", &RigidBody::from_box, py::arg("mass"), py::arg("half_extents"), "Solid box.")
      .def_static("from_sphere", &RigidBody::from_sphere, py::arg("mass"), py::arg("radius"), "Solid sphere.")
      .def_static("from_capsule", &RigidBody::from_capsule, py::arg("mass"), py::arg("radius"), py::arg("half_height"),
                  "Solid capsule along local Y: radius and half height of the cylinder part.");

  py::class_<TendonPathElement>(m, "TendonPathElement",
                                "An element of a spatial tendon's path (ModelBuilder.add_spatial_tendon): its kind, "
                                "body (-1: the world), frame in the body's frame (a site's point; a sphere's centre, "
                                "a cylinder's pose with its axis along z) and size (a radius, a pulley's divisor).")
      .def(py::init([](TendonPathKind kind, int body, const Transform& frame, Scalar size) {
             return TendonPathElement{kind, body, frame, size};
           }),
           py::arg("kind"), py::arg("body"), py::arg("frame") = Transform::identity(), py::arg("size") = 0.0)
      .def_readwrite("kind", &TendonPathElement::kind)
      .def_readwrite("body", &TendonPathElement::body)
      .def_readwrite("frame", &TendonPathElement::frame)
      .def_readwrite("size", &TendonPathElement::size);

  py::class_<JointDofConfig>(m, "JointDofConfig", "Axis, limits, armature, damping and spring of a joint's dofs.")
      .def(py::init<>())
      .def_readwrite("axis", &JointDofConfig::axis)
      .def_readwrite("limit_lower", &JointDofConfig::limit_lower)
      .def_readwrite("limit_upper", &JointDofConfig::limit_upper)
      .def_readwrite("armature", &JointDofConfig::armature)
      .def_readwrite("damping", &JointDofConfig::damping)
      .def_readwrite("frictionloss", &JointDofConfig::frictionloss)
      .def_readwrite("stiffness", &JointDofConfig::stiffness)
      .def_readwrite("q_ref", &JointDofConfig::q_ref)
      .def_readwrite("q0", &JointDofConfig::q0, "Initial coordinate (Revolute, Prismatic).")
      .def_readwrite("target_ke", &JointDofConfig::target_ke)
      .def_readwrite("target_kd", &JointDofConfig::target_kd)
      .def_readwrite("limit_solref", &JointDofConfig::limit_solref,
                     "Softness of its limits' rows (MuJoCo's solreflimit): (0, 0) hard rows, else (time constant, "
                     "damping ratio) or (-stiffness, -damping).")
      .def_readwrite("limit_solimp", &JointDofConfig::limit_solimp, "MuJoCo's solimplimit.")
      .def_readwrite("friction_solref", &JointDofConfig::friction_solref,
                     "Softness of its dry friction's row (MuJoCo's solreffriction), as limit_solref.")
      .def_readwrite("friction_solimp", &JointDofConfig::friction_solimp, "MuJoCo's solimpfriction.");

  auto builder = py::class_<ModelBuilder>(m, "ModelBuilder", "Builds a Model; every call checks its arguments.");
  builder
      .def(py::init([](const std::optional<Vec3>& gravity) {
             return gravity ? std::make_unique<ModelBuilder>(*gravity) : std::make_unique<ModelBuilder>();
           }),
           py::arg("gravity") = py::none(),
           "A builder of gravity `gravity`; without it, (0, -9.81, 0) until a builder or file added to it gives "
           "one (add_builder, replicate, build_worlds, add_mjcf take theirs; two given ones that differ raise).")
      .def_property("gravity", &ModelBuilder::gravity, &ModelBuilder::set_gravity)
      .def_property_readonly("gravity_given", &ModelBuilder::gravity_given,
                             "Whether gravity was given (gravity=, the setter, a file or builder added).")
      .def_property("precision", &ModelBuilder::precision, &ModelBuilder::set_precision,
                    "Precision the solver's batched kernels step the finalized model in (Precision.Float64).")
      .def_property("timestep", &ModelBuilder::timestep, &ModelBuilder::set_timestep,
                    "The step the scene is made for, in s (a file's <option timestep>; 0.002 by default): "
                    "model.timestep.")
      .def_property_readonly("body_count", &ModelBuilder::body_count)
      .def_property_readonly("joint_count", &ModelBuilder::joint_count)
      .def_property_readonly("shape_count", &ModelBuilder::shape_count)
      .def(
          "add_body",
          [](ModelBuilder& self, const RigidBody& body, std::optional<Transform> xform, const std::string& name) {
            return self.add_body(body, xform.value_or(Transform::identity()), name);
          },
          py::arg("body"), py::kw_only(), py::arg("xform") = py::none(), py::arg("name") = "",
          "Adds a body and returns its index; xform is its initial pose (free bodies, Free joints).")
      .def("set_fluid", &ModelBuilder::set_fluid, py::arg("density"), py::arg("viscosity"),
           py::arg("wind") = Vec3::Zero(),
           "The medium the bodies move through (MuJoCo's <option density viscosity wind>, its inertia-box fluid "
           "forces): density kg/m^3 and viscosity Pa s >= 0, wind m/s.")
      .def(
          "add_fluid_ellipsoid",
          [](ModelBuilder& self, int body, const Transform& frame, const Vec3& semi_axes, Scalar blunt_drag,
             Scalar slender_drag, Scalar angular_drag, Scalar kutta_lift, Scalar magnus_lift,
             std::optional<Vec3> added_mass, std::optional<Vec3> added_inertia) {
            FluidEllipsoidOptions o;
            o.blunt_drag = blunt_drag, o.slender_drag = slender_drag, o.angular_drag = angular_drag;
            o.kutta_lift = kutta_lift, o.magnus_lift = magnus_lift;
            if (added_mass) o.added_mass = *added_mass;
            if (added_inertia) o.added_inertia = *added_inertia;
            return self.add_fluid_ellipsoid(body, frame, semi_axes, o);
          },
          py::arg("body"), py::arg("frame"), py::arg("semi_axes"), py::kw_only(), py::arg("blunt_drag") = 0.5,
          py::arg("slender_drag") = 0.25, py::arg("angular_drag") = 1.5, py::arg("kutta_lift") = 1.0,
          py::arg("magnus_lift") = 1.0, py::arg("added_mass") = std::nullopt, py::arg("added_inertia") = std::nullopt,
          "The body feels the fluid (set_fluid) as MuJoCo's ellipsoid model of an ellipsoid at `frame` (in the "
          "body's frame) with these semi-axes, in place of the box of its inertia: added mass, viscous and quadratic "
          "drag, Kutta and Magnus lift (MuJoCo's fluidcoef and defaults); added_mass and added_inertia are the "
          "fluid's virtual mass and moments of inertia per unit density (None: the ellipsoid's own).")
      .def("set_body_gravcomp", &ModelBuilder::set_body_gravcomp, py::arg("body"), py::arg("gravcomp"),
           "The share of the body's weight a force through its centre of mass carries (MuJoCo's gravcomp: 0 none, "
           "1 it floats).")
      .def("add_articulation", &ModelBuilder::add_articulation, py::arg("joints"))
      .def("add_motor", &ModelBuilder::add_motor, py::arg("joint"), py::kw_only(), py::arg("gear") = 1.0,
           py::arg("ctrl_lower") = -INFINITY, py::arg("ctrl_upper") = INFINITY, py::arg("force_lower") = -INFINITY,
           py::arg("force_upper") = INFINITY, py::arg("name") = "",
           "Motor on a Revolute/Prismatic joint: tau = gear * clamp(clamp(ctrl, ctrl range), force range).")
      .def(
          "add_actuator",
          [](ModelBuilder& self, int joint, Scalar gear, Scalar gain, const Vec3& bias, Scalar ctrl_lower,
             Scalar ctrl_upper, Scalar force_lower, Scalar force_upper, const std::string& name) {
            return self.add_actuator(
                joint, actuator_options(gear, ctrl_lower, ctrl_upper, force_lower, force_upper, name, gain, bias));
          },
          py::arg("joint"), py::kw_only(), py::arg("gear") = 1.0, py::arg("gain") = 1.0, py::arg("bias") = Vec3::Zero(),
          py::arg("ctrl_lower") = -INFINITY, py::arg("ctrl_upper") = INFINITY, py::arg("force_lower") = -INFINITY,
          py::arg("force_upper") = INFINITY, py::arg("name") = "",
          "MuJoCo's affine actuator on a Revolute/Prismatic joint: force = clamp(gain * clamp(ctrl) + bias[0] + "
          "bias[1] * gear * q + bias[2] * gear * qd, force range), tau = gear * force; its position and velocity "
          "terms are integrated implicitly.")
      .def(
          "add_position",
          [](ModelBuilder& self, int joint, Scalar kp, Scalar kv, Scalar gear, Scalar ctrl_lower, Scalar ctrl_upper,
             Scalar force_lower, Scalar force_upper, const std::string& name) {
            return self.add_position(joint, kp, kv,
                                     actuator_options(gear, ctrl_lower, ctrl_upper, force_lower, force_upper, name));
          },
          py::arg("joint"), py::kw_only(), py::arg("kp"), py::arg("kv") = 0.0, py::arg("gear") = 1.0,
          py::arg("ctrl_lower") = -INFINITY, py::arg("ctrl_upper") = INFINITY, py::arg("force_lower") = -INFINITY,
          py::arg("force_upper") = INFINITY, py::arg("name") = "",
          "Position servo (MuJoCo's position actuator): gain kp, bias [0, -kp, -kv]; ctrl is the target.")
      .def(
          "add_velocity",
          [](ModelBuilder& self, int joint, Scalar kv, Scalar gear, Scalar ctrl_lower, Scalar ctrl_upper,
             Scalar force_lower, Scalar force_upper, const std::string& name) {
            return self.add_velocity(joint, kv,
                                     actuator_options(gear, ctrl_lower, ctrl_upper, force_lower, force_upper, name));
          },
          py::arg("joint"), py::kw_only(), py::arg("kv"), py::arg("gear") = 1.0, py::arg("ctrl_lower") = -INFINITY,
          py::arg("ctrl_upper") = INFINITY, py::arg("force_lower") = -INFINITY, py::arg("force_upper") = INFINITY,
          py::arg("name") = "", "Velocity servo (MuJoCo's velocity actuator): gain kv, bias [0, 0, -kv].")
      .def(
          "add_tendon",
          [](ModelBuilder& self, const std::vector<int>& joints, const std::vector<Scalar>& coefs, Scalar stiffness,
             Scalar damping, Scalar rest_length, Scalar limit_lower, Scalar limit_upper, const std::string& name,
             const std::array<Scalar, 2>& limit_solref, const std::array<Scalar, 5>& limit_solimp, Scalar frictionloss,
             const std::array<Scalar, 2>& friction_solref, const std::array<Scalar, 5>& friction_solimp) {
            return self.add_tendon(joints, coefs,
                                   {stiffness, damping, rest_length, limit_lower, limit_upper, name, limit_solref,
                                    limit_solimp, frictionloss, friction_solref, friction_solimp});
          },
          py::arg("joints"), py::arg("coefs"), py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
          py::arg("rest_length") = NAN, py::arg("limit_lower") = -INFINITY, py::arg("limit_upper") = INFINITY,
          py::arg("name") = "", py::arg("limit_solref") = std::array<Scalar, 2>{0, 0},
          py::arg("limit_solimp") = std::array<Scalar, 5>{0.9, 0.95, 0.001, 0.5, 2}, py::arg("frictionloss") = 0.0,
          py::arg("friction_solref") = std::array<Scalar, 2>{0, 0},
          py::arg("friction_solimp") = std::array<Scalar, 5>{0.9, 0.95, 0.001, 0.5, 2},
          "Fixed tendon: length = sum coefs[i] * q(joints[i]) over Revolute/Prismatic joints, with a spring "
          "(rest_length NaN: its length at the initial coordinates) and damper, taken explicitly, and limits kept by "
          "rows of the step (soft as MuJoCo's where limit_solref is not (0, 0): JointDofConfig.limit_solref), and its "
          "dry friction (frictionloss, soft by friction_solref). "
          "finalize() joins its joints' articulations into one where they have a fixed base and "
          "follow one another (a gripper's fingers on a static palm); a floating one or one given by "
          "add_articulation is an error.")
      .def(
          "add_spatial_tendon",
          [](ModelBuilder& self, const std::vector<TendonPathElement>& path, Scalar stiffness, Scalar damping,
             Scalar rest_length, Scalar limit_lower, Scalar limit_upper, const std::string& name,
             const std::array<Scalar, 2>& limit_solref, const std::array<Scalar, 5>& limit_solimp, Scalar frictionloss,
             const std::array<Scalar, 2>& friction_solref, const std::array<Scalar, 5>& friction_solimp) {
            return self.add_spatial_tendon(
                path, {stiffness, damping, rest_length, limit_lower, limit_upper, name, limit_solref, limit_solimp,
                       frictionloss, friction_solref, friction_solimp});
          },
          py::arg("path"), py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
          py::arg("rest_length") = NAN, py::arg("limit_lower") = -INFINITY, py::arg("limit_upper") = INFINITY,
          py::arg("name") = "", py::arg("limit_solref") = std::array<Scalar, 2>{0, 0},
          py::arg("limit_solimp") = std::array<Scalar, 5>{0.9, 0.95, 0.001, 0.5, 2}, py::arg("frictionloss") = 0.0,
          py::arg("friction_solref") = std::array<Scalar, 2>{0, 0},
          py::arg("friction_solimp") = std::array<Scalar, 5>{0.9, 0.95, 0.001, 0.5, 2},
          "Spatial tendon (MuJoCo's spatial tendon): its length is its path's (TendonPathElement list), site to "
          "site, around each sphere or cylinder between two sites the straight piece would pass through (on its "
          "side site's side where one follows it), the pieces after a pulley divided by its divisor; spring, damper, "
          "limits and dry friction as add_tendon's, its forces pulling the sites and wraps. The path starts and ends "
          "at a site; its bodies are in at most two articulations.")
      .def(
          "add_tendon_actuator",
          [](ModelBuilder& self, int tendon, Scalar gear, Scalar gain, const Vec3& bias, Scalar ctrl_lower,
             Scalar ctrl_upper, Scalar force_lower, Scalar force_upper, const std::string& name) {
            return self.add_tendon_actuator(
                tendon, actuator_options(gear, ctrl_lower, ctrl_upper, force_lower, force_upper, name, gain, bias));
          },
          py::arg("tendon"), py::kw_only(), py::arg("gear") = 1.0, py::arg("gain") = 1.0,
          py::arg("bias") = Vec3::Zero(), py::arg("ctrl_lower") = -INFINITY, py::arg("ctrl_upper") = INFINITY,
          py::arg("force_lower") = -INFINITY, py::arg("force_upper") = INFINITY, py::arg("name") = "",
          "add_actuator's affine actuator on a tendon (its length and velocity in place of a joint's), taken "
          "explicitly.")
      .def(
          "add_site_actuator",
          [](ModelBuilder& self, int body, const Transform& site, const std::array<Scalar, 6>& gear, Scalar gain,
             const Vec3& bias, Scalar ctrl_lower, Scalar ctrl_upper, Scalar force_lower, Scalar force_upper,
             const std::string& name) {
            return self.add_site_actuator(
                body, site, gear,
                actuator_options(1, ctrl_lower, ctrl_upper, force_lower, force_upper, name, gain, bias));
          },
          py::arg("body"), py::arg("site"), py::kw_only(), py::arg("gear"), py::arg("gain") = 1.0,
          py::arg("bias") = Vec3::Zero(), py::arg("ctrl_lower") = -INFINITY, py::arg("ctrl_upper") = INFINITY,
          py::arg("force_lower") = -INFINITY, py::arg("force_upper") = INFINITY, py::arg("name") = "",
          "An actuator on a site (MuJoCo's site transmission, a thruster): add_actuator's force f with no position or "
          "velocity term (bias[2] must be 0) pushes the body at the site (its frame in the body's) with the force "
          "f * gear[0:3] and the torque f * gear[3:6], both in the site frame.")
      .def_property_readonly("tendon_count", &ModelBuilder::tendon_count)
      .def("add_connect", &ModelBuilder::add_connect, py::arg("body1"), py::arg("body2"), py::arg("anchor"),
           py::arg("name") = "", py::arg("anchor2") = Vec3::Constant(NAN),
           "Equality (MuJoCo's connect): the point anchor of body1 (its frame) stays on the point of body2 (-1: the "
           "world) that coincides with it at the initial coordinates, or on anchor2 (body2's frame) if given.")
      .def("add_weld", &ModelBuilder::add_weld, py::arg("body1"), py::arg("body2"), py::arg("name") = "",
           py::arg("anchor") = Vec3::Zero(), py::arg("relative") = std::nullopt,
           "Equality (MuJoCo's weld): body2 (-1: the world) held to body1 in the pose relative (body2's frame in "
           "body1's; default: as at the initial coordinates), its point anchor (its frame) kept in place.")
      .def("add_joint_coupling", &ModelBuilder::add_joint_coupling, py::arg("joint1"), py::arg("joint2"),
           py::arg("poly"), py::arg("name") = "",
           "Equality (MuJoCo's joint): q1 - q1_0 = poly[0] + poly[1] x + ... + poly[4] x^4, x = q2 - q2_0, for "
           "Revolute/Prismatic joints (joint2 -1: x = 0).")
      .def("set_equality_softness", &ModelBuilder::set_equality_softness, py::arg("equality"), py::arg("solref"),
           py::arg("solimp") = std::array<Scalar, 5>{0.9, 0.95, 0.001, 0.5, 2},
           "Makes an equality's rows soft as MuJoCo's solref and solimp (JointDofConfig.limit_solref says how; "
           "hard rows until this is called).")
      .def_property_readonly("equality_count", &ModelBuilder::equality_count)
      .def(
          "add_sensor",
          [](ModelBuilder& self, const py::object& type, int object, const Transform& xform,
             std::optional<ShapeType> zone_type, const Vec3& zone_size, Scalar cutoff, int shape,
             const std::string& name) {
            SensorOptions options;
            options.xform = xform;
            options.zone_type = zone_type ? static_cast<int>(*zone_type) : -1;
            options.zone_size = zone_size;
            options.cutoff = cutoff;
            options.shape = shape;
            options.name = name;
            return self.add_sensor(sensor_type_of(type), object, options);
          },
          py::arg("type"), py::arg("object"), py::kw_only(), py::arg("xform") = Transform::identity(),
          py::arg("zone_type") = std::nullopt, py::arg("zone_size") = Vec3::Zero(), py::arg("cutoff") = 0.0,
          py::arg("shape") = -1, py::arg("name") = "",
          "A sensor (a SensorType, or its name as MJCF writes it: 'gyro') of `object`: a joint (jointpos, jointvel, "
          "ballquat, ballangvel), a tendon (tendonpos, tendonvel) or a body (-1: the world) with its frame xform in "
          "the body's frame. A touch sensor sums the normal forces of its body's contacts whose ray meets its zone "
          "(zone_type Sphere, Box, Ellipsoid, Capsule or Cylinder of zone_size, in the frame; None: the whole body); "
          "a touch or contactforce sensor with a shape reads only that shape's contacts. "
          "Values are clamped to [-cutoff, cutoff] where cutoff > 0. A solver's step writes them into "
          "State.sensor_data (from the state it starts from, with its accelerations and contact forces: MuJoCo's "
          "sensordata after mj_step).")
      .def_property_readonly("sensor_count", &ModelBuilder::sensor_count)
      .def_property("friction_rule", &ModelBuilder::friction_rule, &ModelBuilder::set_friction_rule,
                    "How contacts combine their shapes' friction; add_mjcf sets Mujoco.")
      .def_property("collision_filter", &ModelBuilder::collision_filter, &ModelBuilder::set_collision_filter,
                    "The rule shape collision groups and masks filter pairs by; add_mjcf sets Mujoco.")
      .def("exclude_shapes", &ModelBuilder::exclude_shapes, py::arg("a"), py::arg("b"), "Shapes a and b never collide.")
      .def("exclude_bodies", &ModelBuilder::exclude_bodies, py::arg("body_a"), py::arg("body_b"),
           "No shape of body_a collides with a shape of body_b (those added so far; -1: static shapes).")
      .def("add_keyframe", &ModelBuilder::add_keyframe, py::arg("name"), py::arg("joint_q"),
           py::arg("joint_qd") = std::vector<Scalar>{}, py::arg("ctrl") = std::vector<Scalar>{},
           "A keyframe over the joints and actuators added so far (joint_qd and ctrl default to zero); keyframes of "
           "one name from several builders make one keyframe of the model.")
      .def_property_readonly("actuator_count", &ModelBuilder::actuator_count)
      .def_property_readonly("world_count", &ModelBuilder::world_count)
      .def(
          "add_builder",
          [](ModelBuilder& self, const ModelBuilder& other, std::optional<Transform> xform, int world) {
            self.add_builder(other, xform.value_or(Transform::identity()), world);
          },
          py::arg("other"), py::kw_only(), py::arg("xform") = py::none(), py::arg("world") = -1,
          "Appends everything of other as world `world` (-1: a new world), placed by xform.")
      .def("replicate", &ModelBuilder::replicate, py::arg("other"), py::arg("world_count"),
           py::arg("spacing") = Vec3::Zero(), "world_count copies of other, copy i shifted by i * spacing.")
      .def(
          "add_ground_plane",
          [](ModelBuilder& self, Scalar y, SHAPE_PARAMS) {
            return self.add_ground_plane(y, shape_options(std::nullopt, SHAPE_VALUES));
          },
          py::arg("y") = 0.0, py::kw_only(), SHAPE_KWARGS, "Static plane y = const with normal +Y.")
      .def(
          "add_plane",
          [](ModelBuilder& self, const Vec3& normal, Scalar offset, SHAPE_PARAMS) {
            return self.add_plane(normal, offset, shape_options(std::nullopt, SHAPE_VALUES));
          },
          py::arg("normal"), py::arg("offset") = 0.0, py::kw_only(), SHAPE_KWARGS,
          "Static plane {x : normal . x = offset}.")
      .def(
          "add_shape_box",
          [](ModelBuilder& self, int body, const Vec3& half_extents, std::optional<Transform> xform, SHAPE_PARAMS) {
            return self.add_shape_box(body, half_extents, shape_options(xform, SHAPE_VALUES));
          },
          py::arg("body"), py::arg("half_extents"), XFORM_KWARG, SHAPE_KWARGS)
      .def(
          "add_shape_sphere",
          [](ModelBuilder& self, int body, Scalar radius, std::optional<Transform> xform, SHAPE_PARAMS) {
            return self.add_shape_sphere(body, radius, shape_options(xform, SHAPE_VALUES));
          },
          py::arg("body"), py::arg("radius"), XFORM_KWARG, SHAPE_KWARGS)
      .def(
          "add_shape_capsule",
          [](ModelBuilder& self, int body, Scalar radius, Scalar half_height, std::optional<Transform> xform,
             SHAPE_PARAMS) {
            return self.add_shape_capsule(body, radius, half_height, shape_options(xform, SHAPE_VALUES));
          },
          py::arg("body"), py::arg("radius"), py::arg("half_height"), XFORM_KWARG, SHAPE_KWARGS,
          "Capsule along the shape frame's local Y axis.")
      .def(
          "add_shape_cylinder",
          [](ModelBuilder& self, int body, Scalar radius, Scalar half_height, std::optional<Transform> xform,
             SHAPE_PARAMS) {
            return self.add_shape_cylinder(body, radius, half_height, shape_options(xform, SHAPE_VALUES));
          },
          py::arg("body"), py::arg("radius"), py::arg("half_height"), XFORM_KWARG, SHAPE_KWARGS,
          "Cylinder along the shape frame's local Y axis.")
      .def(
          "add_shape_ellipsoid",
          [](ModelBuilder& self, int body, const Vec3& radii, std::optional<Transform> xform, SHAPE_PARAMS) {
            return self.add_shape_ellipsoid(body, radii, shape_options(xform, SHAPE_VALUES));
          },
          py::arg("body"), py::arg("radii"), XFORM_KWARG, SHAPE_KWARGS,
          "Ellipsoid of semi-axes radii along the shape frame's X, Y and Z.")
      .def(
          "add_mesh",
          [](ModelBuilder& self, const Eigen::Matrix<Scalar, Eigen::Dynamic, 3, Eigen::RowMajor>& vertices,
             const std::string& name) {
            std::vector<Vec3> points(vertices.rows());
            for (Eigen::Index i = 0; i < vertices.rows(); ++i) points[i] = vertices.row(i).transpose();
            return self.add_mesh(points, name);
          },
          py::arg("vertices"), py::kw_only(), py::arg("name") = "",
          "A mesh from its vertices (n x 3) for add_shape_mesh; it collides as their convex hull.")
      .def(
          "add_shape_mesh",
          [](ModelBuilder& self, int body, int mesh, std::optional<Transform> xform, SHAPE_PARAMS) {
            return self.add_shape_mesh(body, mesh, shape_options(xform, SHAPE_VALUES));
          },
          py::arg("body"), py::arg("mesh"), XFORM_KWARG, SHAPE_KWARGS,
          "A shape of mesh `mesh` (add_mesh), colliding as its convex hull.")
      .def("add_mjcf", &import_file<&ModelBuilder::add_mjcf>, py::arg("path"), py::kw_only(),
           py::arg("xform") = py::none(), py::arg("static_shapes") = true,
           "Imports an MJCF file through MuJoCo's parser, its world frame placed at xform (static_shapes=False "
           "leaves out the world's geoms, such as a floor); warns (UserWarning) about what is not modelled and "
           "returns those warnings.")
      .def("add_urdf", &import_file<&ModelBuilder::add_urdf>, py::arg("path"), py::kw_only(),
           py::arg("xform") = py::none(), py::arg("static_shapes") = true,
           "Imports a URDF file through MuJoCo's parser; warns like add_mjcf.")
      .def("finalize", &ModelBuilder::finalize, "Lays the scene out as a Model.");
  def_joint(builder, "add_joint_revolute", JointType::Revolute, "Revolute joint: rotation by q about axis.");
  def_joint(builder, "add_joint_prismatic", JointType::Prismatic, "Prismatic joint: translation by q along axis.");
  def_joint(builder, "add_joint_slide", JointType::Prismatic, "Alias of add_joint_prismatic.");
  def_joint(builder, "add_joint_ball", JointType::Ball,
            "Ball joint: quaternion q, angular velocity in the child frame.");
  def_joint(builder, "add_joint_fixed", JointType::Fixed, "Fixed joint: rigid attachment.");
  def_joint(builder, "add_joint_free", JointType::Free, "Free joint (root only): q = pose, qd = [w; v] in the world.");
  // the maximal-coordinate joints (SolverSemiImplicit, SolverXPBD)
  auto joint_frames = [](std::optional<Transform> parent_xform, std::optional<Transform> child_xform,
                         const std::string& name) {
    JointOptions options;
    options.parent_xform = parent_xform.value_or(Transform::identity());
    options.child_xform = child_xform.value_or(Transform::identity());
    options.name = name;
    return options;
  };
  builder
      .def(
          "add_joint_distance",
          [joint_frames](ModelBuilder& self, int parent, int child, std::optional<Transform> parent_xform,
                         std::optional<Transform> child_xform, Scalar min_distance, Scalar max_distance,
                         Scalar compliance, const std::string& name) {
            return self.add_joint_distance(parent, child, joint_frames(parent_xform, child_xform, name), min_distance,
                                           max_distance, compliance);
          },
          py::arg("parent"), py::arg("child"), py::kw_only(), py::arg("parent_xform") = py::none(),
          py::arg("child_xform") = py::none(), py::arg("min_distance") = 0.0, py::arg("max_distance") = INFINITY,
          py::arg("compliance") = 0.0, py::arg("name") = "",
          "Distance joint (maximal coordinates): the joint frames' origins stay between min_distance and "
          "max_distance apart; compliance (m/N) makes it a spring of stiffness 1 / compliance. Enforced by "
          "SolverSemiImplicit and SolverXPBD; SolverFeatherstone refuses it.")
      .def(
          "add_joint_d6",
          [joint_frames](ModelBuilder& self, int parent, int child, std::optional<Transform> parent_xform,
                         std::optional<Transform> child_xform, const py::list& linear_axes,
                         const py::list& angular_axes, Scalar linear_compliance, Scalar angular_compliance,
                         const std::string& name) {
            std::vector<JointDofConfig> linear, angular;
            for (const py::handle axis : linear_axes)
              linear.push_back(dof_config(py::reinterpret_borrow<py::object>(axis)));
            for (const py::handle axis : angular_axes)
              angular.push_back(dof_config(py::reinterpret_borrow<py::object>(axis)));
            return self.add_joint_d6(parent, child, joint_frames(parent_xform, child_xform, name), linear, angular,
                                     linear_compliance, angular_compliance);
          },
          py::arg("parent"), py::arg("child"), py::kw_only(), py::arg("parent_xform") = py::none(),
          py::arg("child_xform") = py::none(), py::arg("linear_axes") = py::list(),
          py::arg("angular_axes") = py::list(), py::arg("linear_compliance") = 0.0, py::arg("angular_compliance") = 0.0,
          py::arg("name") = "",
          "D6 joint (maximal coordinates): each axis of the joint frame locked, free, limited or driven. "
          "linear_axes and angular_axes (JointDofConfig or 3 numbers each, at most 3 of each kind) are the axes "
          "that are not locked, with their limits and drive gains; the joint frame turns so its x, y, z are the "
          "distinct given axes in order (linear first), completed to a right-handed frame; its dofs are angular x, y, "
          "z then linear x, y, z of that frame. Enforced by SolverSemiImplicit and SolverXPBD.")
      .def(
          "add_joint_cable",
          [joint_frames](ModelBuilder& self, int parent, int child, std::optional<Transform> parent_xform,
                         std::optional<Transform> child_xform, Scalar stretch_compliance, Scalar bend_compliance,
                         const std::string& name) {
            return self.add_joint_cable(parent, child, joint_frames(parent_xform, child_xform, name),
                                        stretch_compliance, bend_compliance);
          },
          py::arg("parent"), py::arg("child"), py::kw_only(), py::arg("parent_xform") = py::none(),
          py::arg("child_xform") = py::none(), py::arg("stretch_compliance") = 0.0, py::arg("bend_compliance") = 0.0,
          py::arg("name") = "",
          "Cable joint (maximal coordinates): a segment of a rope or cable held to its parent segment at the joint "
          "frames, stretching with stretch_compliance (m/N) and bending and twisting with bend_compliance "
          "(rad/(N m)). Enforced by SolverSemiImplicit and SolverXPBD.");
}

}  // namespace novaphy::python
