#include "engine/model/builder.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/model/body_kinematics.h"
#include "engine/model/builder_checks.h"
#include "engine/model/error.h"
#include "engine/model/spatial_tendon.h"

namespace novaphy {

RigidBody RigidBody::from_box(Scalar mass, const Vec3& half_extents) {
  const Vec3 s = 4 * half_extents.cwiseProduct(half_extents);  // full extents squared
  RigidBody b;
  b.mass = mass;
  b.inertia = (mass / 12 * Vec3(s.y() + s.z(), s.x() + s.z(), s.x() + s.y())).asDiagonal();
  return b;
}

RigidBody RigidBody::from_sphere(Scalar mass, Scalar radius) {
  RigidBody b;
  b.mass = mass;
  b.inertia = Mat3::Identity() * (0.4 * mass * radius * radius);
  return b;
}

RigidBody RigidBody::from_capsule(Scalar mass, Scalar radius, Scalar half_height) {
  // cylinder of length 2 h plus two hemispheres, uniform density, axis along local Y
  const Scalar r2 = radius * radius, h = half_height;
  const Scalar v_cyl = M_PI * r2 * 2 * h, v_sph = 4.0 / 3.0 * M_PI * r2 * radius;
  const Scalar m_cyl = mass * v_cyl / (v_cyl + v_sph), m_sph = mass - m_cyl;
  const Scalar I_axis = m_cyl * r2 / 2 + m_sph * 0.4 * r2;
  const Scalar I_perp = m_cyl * (r2 / 4 + h * h / 3) + m_sph * (0.4 * r2 + h * h + 0.75 * h * radius);
  RigidBody b;
  b.mass = mass;
  b.inertia = Vec3(I_perp, I_axis, I_perp).asDiagonal();
  return b;
}

ModelBuilder::ModelBuilder(const Vec3& gravity) { set_gravity(gravity); }

void ModelBuilder::set_precision(Precision precision) {
  if (precision != Precision::Float64 && precision != Precision::Float32)
    fail("builder: precision must be Float64 or Float32, got ", static_cast<int>(precision));
  precision_ = precision;
  precision_given_ = true;
}

void ModelBuilder::set_gravity(const Vec3& gravity) {
  check_finite("builder", "gravity", gravity);
  gravity_ = gravity;
  gravity_given_ = true;
}

void ModelBuilder::set_timestep(Scalar timestep) {
  if (!(timestep > 0 && std::isfinite(timestep))) fail("builder: timestep must be finite and > 0, got ", timestep);
  timestep_ = timestep;
  timestep_given_ = true;
}

namespace {

std::string vec_text(const Vec3& v) {
  std::ostringstream os;
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

}  // namespace

void ModelBuilder::take_gravity(const Vec3& gravity, const char* source) {
  if (gravity_given_ && gravity != gravity_)
    fail(source, " gravity ", vec_text(gravity), " differs from the builder's ", vec_text(gravity_),
         " (give both the same gravity, or make the builder without gravity= to take the added one)");
  set_gravity(gravity);
}

void ModelBuilder::take_timestep(Scalar timestep) {
  if (!timestep_given_) set_timestep(timestep);
}

void ModelBuilder::take_settings(const ModelBuilder& other) {
  if (other.precision_given_ && precision_given_ && other.precision_ != precision_)
    fail("add_builder: the added builder's precision ", precision_name(other.precision_),
         " differs from the builder's ", precision_name(precision_));
  if (other.gravity_given_) take_gravity(other.gravity_, "add_builder: the added builder's");
  if (other.timestep_given_) take_timestep(other.timestep_);
  if (other.precision_given_) set_precision(other.precision_);
}

int ModelBuilder::add_body(const RigidBody& body, const Transform& xform, const std::string& name) {
  return add_body_checked(body, xform, name, false);
}

int ModelBuilder::add_body_checked(const RigidBody& body, const Transform& xform, const std::string& name,
                                   bool allow_massless) {
  const std::string item = label("body", body_count(), name);
  check_rigid_body(item, body, allow_massless);
  body_xform_.push_back(checked_transform(item, "xform", xform));
  body_mass_.push_back(body.mass);
  body_gravcomp_.push_back(0);
  body_com_.push_back(body.com);
  body_inertia_.push_back(0.5 * (body.inertia + body.inertia.transpose()));
  body_name_.push_back(name);
  body_joint_.push_back(-1);
  body_world_.push_back(0);
  world_count_ = std::max(world_count_, 1);
  return body_count() - 1;
}

void ModelBuilder::set_body_gravcomp(int body, Scalar gravcomp) {
  if (body < 0 || body >= body_count()) fail("set_body_gravcomp: body ", body, " out of range [0, ", body_count(), ")");
  check_finite(label("body", body, body_name_[body]), "gravcomp", gravcomp);
  body_gravcomp_[body] = gravcomp;
}

int ModelBuilder::add_joint_revolute(int parent, int child, const JointOptions& options) {
  return add_joint(JointType::Revolute, parent, child, options);
}
int ModelBuilder::add_joint_prismatic(int parent, int child, const JointOptions& options) {
  return add_joint(JointType::Prismatic, parent, child, options);
}
int ModelBuilder::add_joint_ball(int parent, int child, const JointOptions& options) {
  return add_joint(JointType::Ball, parent, child, options);
}
int ModelBuilder::add_joint_fixed(int parent, int child, const JointOptions& options) {
  return add_joint(JointType::Fixed, parent, child, options);
}
int ModelBuilder::add_joint_free(int parent, int child, const JointOptions& options) {
  return add_joint(JointType::Free, parent, child, options);
}

int ModelBuilder::add_joint(JointType type, int parent, int child, const JointOptions& options) {
  if (joint_is_six_dof(type) && type != JointType::Free)
    fail(label("joint", joint_count(), options.name), " (", joint_type_name(type), "): add it with add_joint_",
         type == JointType::Distance ? "distance"
         : type == JointType::D6     ? "d6"
                                     : "cable");
  return add_joint_record({type, parent, child, options});
}

namespace {

// a dof's limits and gains checked
void check_dof(const std::string& item, const JointDofConfig& dof) {
  if (std::isnan(dof.limit_lower) || std::isnan(dof.limit_upper) || dof.limit_lower > dof.limit_upper)
    fail(item, ": limits must satisfy limit_lower <= limit_upper, got [", dof.limit_lower, ", ", dof.limit_upper, "]");
  check_nonnegative(item, "armature", dof.armature);
  check_nonnegative(item, "damping", dof.damping);
  check_nonnegative(item, "frictionloss", dof.frictionloss);
  check_nonnegative(item, "stiffness", dof.stiffness);
  check_nonnegative(item, "target_ke", dof.target_ke);
  check_nonnegative(item, "target_kd", dof.target_kd);
  check_finite(item, "q_ref", dof.q_ref);
  check_finite(item, "q0", dof.q0);
  check_solref(item, "limit_solref", dof.limit_solref);
  check_solimp(item, "limit_solimp", dof.limit_solimp);
  check_solref(item, "friction_solref", dof.friction_solref);
  check_solimp(item, "friction_solimp", dof.friction_solimp);
}

}  // namespace

int ModelBuilder::add_joint_record(JointRecord joint) {
  const JointType type = joint.type;
  const int parent = joint.parent, child = joint.child;
  const std::string item = label("joint", joint_count(), joint.options.name) + " (" + joint_type_name(type) + ")";
  if (parent < -1 || parent >= body_count())
    fail(item, ": parent body index ", parent, " out of range [-1, ", body_count(), ")");
  if (child < 0 || child >= body_count())
    fail(item, ": child body index ", child, " out of range [0, ", body_count(), ")");
  if (child == parent) fail(item, ": child body ", child, " is its own parent");
  if (parent >= 0 && body_joint_[parent] < 0)
    fail(item, ": parent body ", parent, " is not yet defined: no joint attaches it yet (add its joint first)");
  if (body_joint_[child] >= 0) fail(item, ": body ", child, " is already the child of joint ", body_joint_[child]);
  if (type == JointType::Free && parent != -1)
    fail(item, ": a Free joint must be a root (parent -1), got parent ", parent);

  joint.options.parent_xform = checked_transform(item, "parent_xform", joint.options.parent_xform);
  joint.options.child_xform = checked_transform(item, "child_xform", joint.options.child_xform);
  JointDofConfig& dof = joint.options.dof;
  if (type == JointType::Revolute || type == JointType::Prismatic) {
    check_finite(item, "axis", dof.axis);
    if (dof.axis.norm() < 1e-9) fail(item, ": axis has zero length");
    dof.axis.normalize();
  }
  check_dof(item, dof);
  for (size_t k = 0; k < joint.dofs.size(); ++k) check_dof(item + " dof " + std::to_string(k), joint.dofs[k]);

  joints_.push_back(joint);
  body_joint_[child] = joint_count() - 1;
  return joint_count() - 1;
}

int ModelBuilder::add_articulation(const std::vector<int>& joints) {
  const std::string item = "articulation " + std::to_string(articulation_count_);
  if (joints.empty()) fail(item, ": no joints");
  for (size_t k = 0; k < joints.size(); ++k) {
    const int j = joints[k];
    if (j < 0 || j >= joint_count()) fail(item, ": joint index ", j, " out of range [0, ", joint_count(), ")");
    if (j != joints[0] + static_cast<int>(k))
      fail(item, ": joints must be contiguous and ascending, got ", j, " after ", joints[k - 1]);
    JointRecord& joint = joints_[j];
    if (joint.articulation >= 0) fail(item, ": joint ", j, " already belongs to articulation ", joint.articulation);
    if (joint.parent >= 0) {
      const int parent_joint = body_joint_[joint.parent];
      if (parent_joint < joints[0])
        fail(item, ": joint ", j, " hangs from body ", joint.parent, " which is not in this articulation");
    }
  }
  for (const int j : joints) joints_[j].articulation = articulation_count_;
  return articulation_count_++;
}

int ModelBuilder::add_actuator(int joint, const ActuatorOptions& options) {
  return add_actuator_of("an actuator", joint, options);
}

void ModelBuilder::check_scalar_joint(const std::string& item, const std::string& needs, int joint) const {
  if (joint < 0 || joint >= joint_count())
    fail(item, ": joint index ", joint, " out of range [0, ", joint_count(), ")");
  const JointType type = joints_[joint].type;
  if (type != JointType::Revolute && type != JointType::Prismatic)
    fail(item, ": ", needs, ", joint ", joint, " is ", joint_type_name(type));
}

int ModelBuilder::add_actuator_of(const char* kind, int joint, const ActuatorOptions& options) {
  const std::string item = label("actuator", actuator_count(), options.name);
  check_scalar_joint(item, std::string(kind) + " drives a Revolute or Prismatic joint", joint);
  check_actuator(item, options);
  actuators_.push_back({joint, options});
  return actuator_count() - 1;
}

int ModelBuilder::add_position(int joint, Scalar kp, Scalar kv, const ActuatorOptions& options) {
  ActuatorOptions servo = options;
  servo.gain = kp;
  servo.bias = Vec3(0, -kp, -kv);
  return add_actuator_of("a position servo", joint, servo);
}

int ModelBuilder::add_velocity(int joint, Scalar kv, const ActuatorOptions& options) {
  ActuatorOptions servo = options;
  servo.gain = kv;
  servo.bias = Vec3(0, 0, -kv);
  return add_actuator_of("a velocity servo", joint, servo);
}

int ModelBuilder::add_motor(int joint, Scalar gear, Scalar ctrl_lower, Scalar ctrl_upper, Scalar force_lower,
                            Scalar force_upper, const std::string& name) {
  return add_actuator_of("a motor", joint,
                         ActuatorOptions::motor(gear, ctrl_lower, ctrl_upper, force_lower, force_upper, name));
}

ModelBuilder::JointRecord ModelBuilder::free_joint(int body) const {
  JointRecord joint{JointType::Free, -1, body, {}};
  joint.options.name = body_name_[body].empty() ? "" : body_name_[body] + "_free";
  return joint;
}

void ModelBuilder::exclude_shapes(int a, int b) {
  for (const int s : {a, b})
    if (s < 0 || s >= shape_count()) fail("exclude_shapes: shape index ", s, " out of range [0, ", shape_count(), ")");
  if (a == b) fail("exclude_shapes: shape ", a, " with itself");
  excluded_.push_back({std::min(a, b), std::max(a, b)});
}

void ModelBuilder::exclude_bodies(int body_a, int body_b) {
  for (const int b : {body_a, body_b})
    if (b < -1 || b >= body_count()) fail("exclude_bodies: body index ", b, " out of range [-1, ", body_count(), ")");
  for (int a = 0; a < shape_count(); ++a)
    for (int b = 0; b < shape_count(); ++b)
      if (a < b && ((shapes_[a].body == body_a && shapes_[b].body == body_b) ||
                    (shapes_[a].body == body_b && shapes_[b].body == body_a)))
        excluded_.push_back({a, b});
}

void ModelBuilder::add_keyframe(const std::string& name, const std::vector<Scalar>& joint_q,
                                const std::vector<Scalar>& joint_qd, const std::vector<Scalar>& ctrl) {
  int coords = 0, dofs = 0;
  for (const JointRecord& joint : joints_) coords += joint_coord_count(joint.type), dofs += joint_dof_count(joint.type);
  const std::string item = "keyframe '" + name + "'";
  if (name.empty()) fail("a keyframe needs a name");
  auto check = [&](const char* what, const std::vector<Scalar>& x, size_t size, bool may_be_empty) {
    if (x.size() != size && !(may_be_empty && x.empty()))
      fail(item, ": ", what, " has ", x.size(), " entries, the joints and actuators added so far need ", size);
    for (size_t k = 0; k < x.size(); ++k)
      if (!std::isfinite(x[k])) fail(item, ": ", what, "[", k, "] is not finite: ", x[k]);
  };
  check("joint_q", joint_q, coords, false);
  check("joint_qd", joint_qd, dofs, true);
  check("ctrl", ctrl, actuators_.size(), true);
  KeyframeRecord key{name, 0, joint_count(), 0, joint_q, joint_qd, ctrl};
  if (key.qd.empty()) key.qd.assign(dofs, 0);
  if (key.ctrl.empty()) key.ctrl.assign(actuators_.size(), 0);
  keyframes_.push_back(std::move(key));
}

void ModelBuilder::lay_out_keyframes(Model& model) const {
  for (const KeyframeRecord& key : keyframes_)
    if (std::find(model.keyframe_name.begin(), model.keyframe_name.end(), key.name) == model.keyframe_name.end())
      model.keyframe_name.push_back(key.name);
  model.keyframe_count = static_cast<int>(model.keyframe_name.size());
  const size_t nq = model.joint_coord_count, nv = model.joint_dof_count, nu = model.actuator_count;
  model.keyframe_q.resize(model.keyframe_count * nq);
  model.keyframe_qd.assign(model.keyframe_count * nv, 0);
  model.keyframe_ctrl.assign(model.keyframe_count * nu, 0);
  // (through data(): a model of no actuators has an empty keyframe_ctrl, which [] may not index)
  for (int k = 0; k < model.keyframe_count; ++k)
    std::copy_n(model.joint_q0.begin(), nq, model.keyframe_q.data() + k * nq);
  for (const KeyframeRecord& key : keyframes_) {
    const size_t k =
        std::find(model.keyframe_name.begin(), model.keyframe_name.end(), key.name) - model.keyframe_name.begin();
    const int q0 = model.joint_q_start[key.joint_begin], qd0 = model.joint_qd_start[key.joint_begin];
    std::copy(key.q.begin(), key.q.end(), model.keyframe_q.data() + k * nq + q0);
    std::copy(key.qd.begin(), key.qd.end(), model.keyframe_qd.data() + k * nv + qd0);
    std::copy(key.ctrl.begin(), key.ctrl.end(), model.keyframe_ctrl.data() + k * nu + key.actuator_begin);
  }
}

void ModelBuilder::add_builder(const ModelBuilder& other, const Transform& xform, int world) {
  if (&other == this) fail("add_builder: a builder cannot be added to itself");
  if (world < -1) fail("add_builder: world must be >= -1, got ", world);
  const Transform place = checked_transform("add_builder", "xform", xform);
  take_settings(other);
  if (world < 0) world = world_count_;
  const int body0 = body_count(), joint0 = joint_count(), shape0 = shape_count();
  for (int b = 0; b < other.body_count(); ++b) {
    body_mass_.push_back(other.body_mass_[b]);
    body_gravcomp_.push_back(other.body_gravcomp_[b]);
    body_com_.push_back(other.body_com_[b]);
    body_inertia_.push_back(other.body_inertia_[b]);
    body_xform_.push_back(place * other.body_xform_[b]);
    body_name_.push_back(other.body_name_[b]);
    body_joint_.push_back(other.body_joint_[b] < 0 ? -1 : other.body_joint_[b] + joint0);
    body_world_.push_back(world);
  }
  for (JointRecord joint : other.joints_) {
    if (joint.parent < 0)
      joint.options.parent_xform = place * joint.options.parent_xform;
    else
      joint.parent += body0;
    joint.child += body0;
    if (joint.articulation >= 0) joint.articulation += articulation_count_;
    joints_.push_back(joint);
  }
  // the copy's free bodies get their Free joints now, so each world's joints stay together
  for (int b = body0; b < body_count(); ++b) {
    if (body_joint_[b] >= 0) continue;
    joints_.push_back(free_joint(b));
    body_joint_[b] = joint_count() - 1;
  }
  articulation_count_ += other.articulation_count_;
  const int mesh0 = static_cast<int>(meshes_.size());
  meshes_.insert(meshes_.end(), other.meshes_.begin(), other.meshes_.end());
  for (int s = 0; s < other.shape_count(); ++s) {
    ShapeRecord shape = other.shapes_[s];
    if (shape.mesh >= 0) shape.mesh += mesh0;
    if (shape.body < 0)
      shape.options.xform = place * shape.options.xform;
    else
      shape.body += body0;
    shapes_.push_back(shape);
    shape_world_.push_back(world);
  }
  for (const auto& [a, b] : other.excluded_) excluded_.push_back({a + shape0, b + shape0});
  if (other.collision_filter_ == CollisionFilter::Mujoco) collision_filter_ = CollisionFilter::Mujoco;
  if (other.friction_rule_ == FrictionRule::Mujoco) friction_rule_ = FrictionRule::Mujoco;
  if (other.impratio_ != 1) impratio_ = other.impratio_;
  if (other.fluid_density_ != 0 || other.fluid_viscosity_ != 0 || !other.wind_.isZero())
    fluid_density_ = other.fluid_density_, fluid_viscosity_ = other.fluid_viscosity_, wind_ = other.wind_;
  for (FluidEllipsoidRecord e : other.fluid_ellipsoids_) {
    e.body += body0;
    fluid_ellipsoids_.push_back(e);
  }
  for (KeyframeRecord key : other.keyframes_) {
    key.joint_begin += joint0;
    key.joint_end += joint0;
    key.actuator_begin += actuator_count();
    keyframes_.push_back(std::move(key));
  }
  for (ActuatorRecord actuator : other.actuators_) {
    if (actuator.joint >= 0) actuator.joint += joint0;
    if (actuator.tendon >= 0) actuator.tendon += tendon_count();
    if (actuator.body >= 0) actuator.body += body0;
    actuators_.push_back(actuator);
  }
  for (EqualityRecord e : other.equalities_) {
    const int offset = e.type == EqualityType::JointCoupling ? joint0 : body0;
    for (int& object : e.object)
      if (object >= 0) object += offset;
    equalities_.push_back(e);
  }
  const int tendon0 = tendon_count();
  for (TendonRecord tendon : other.tendons_) {
    for (int& j : tendon.joints) j += joint0;
    for (TendonPathElement& x : tendon.path) {
      if (x.body >= 0) x.body += body0;
      if (x.body < 0) x.frame = place * x.frame;
    }
    tendons_.push_back(std::move(tendon));
  }
  for (SensorRecord sensor : other.sensors_) {
    const SensorObject kind = sensor_object_kind(sensor.type);
    if (kind == SensorObject::Joint) sensor.object += joint0;
    if (kind == SensorObject::Tendon) sensor.object += tendon0;
    if (kind == SensorObject::Body && sensor.object >= 0) sensor.object += body0;
    if (kind == SensorObject::Body && sensor.object < 0) sensor.options.xform = place * sensor.options.xform;
    if (sensor.options.shape >= 0) sensor.options.shape += shape0;
    sensor.world = world;
    sensors_.push_back(std::move(sensor));
  }
  world_count_ = std::max(world_count_, world + 1);
}

void ModelBuilder::replicate(const ModelBuilder& other, int world_count, const Vec3& spacing) {
  if (world_count < 1) fail("replicate: world_count must be >= 1, got ", world_count);
  check_finite("replicate", "spacing", spacing);
  for (int w = 0; w < world_count; ++w) {
    Transform place;
    place.p = w * spacing;
    add_builder(other, place);
  }
}

std::vector<ModelBuilder::JointRecord> ModelBuilder::articulated_joints(int& articulation_count) const {
  // articulations: explicit ones keep their joints; the others follow their parent's
  // articulation or start a new one at a root; bodies without a joint get a Free joint each
  std::vector<JointRecord> joints = joints_;
  articulation_count = articulation_count_;
  for (JointRecord& joint : joints) {
    if (joint.articulation >= 0) continue;
    joint.articulation = joint.parent < 0 ? articulation_count++ : joints[body_joint_[joint.parent]].articulation;
  }
  join_tendon_articulations(joints, articulation_count);
  for (int b = 0; b < body_count(); ++b) {
    if (body_joint_[b] >= 0) continue;
    joints.push_back(free_joint(b));
    joints.back().articulation = articulation_count++;
  }
  return joints;
}

void ModelBuilder::lay_out_joints(const std::vector<JointRecord>& joints, Model& model) const {
  // articulations must be contiguous runs of joints; number them in joint order
  std::vector<int> articulation_id(model.articulation_count, -1);
  std::vector<int> child_joint(body_count(), -1);
  int q = 0, qd = 0, next_articulation = 0;
  for (int j = 0; j < model.joint_count; ++j) {
    const JointRecord& joint = joints[j];
    int& id = articulation_id[joint.articulation];
    if (id < 0) {
      id = next_articulation++;
      model.articulation_start[id] = j;
    } else if (model.joint_articulation[j - 1] != id) {
      fail(label("joint", j, joint.options.name),
           ": its articulation's joints are not contiguous "
           "(add each articulation's joints one after another)");
    }
    child_joint[joint.child] = j;
    model.joint_type[j] = static_cast<int>(joint.type);
    model.joint_parent[j] = joint.parent;
    model.joint_child[j] = joint.child;
    model.joint_ancestor[j] = joint.parent < 0 ? -1 : child_joint[joint.parent];
    model.joint_articulation[j] = id;
    model.joint_q_start[j] = q;
    model.joint_qd_start[j] = qd;
    joint.options.parent_xform.to_array(&model.joint_X_p[7 * j]);
    joint.options.child_xform.to_array(&model.joint_X_c[7 * j]);
    Eigen::Map<Vec3>(&model.joint_axis[3 * j]) = joint.options.dof.axis;
    for (int k = 0; k < 2; ++k) model.joint_compliance[2 * j + k] = joint.compliance[k];
    model.joint_name.push_back(joint.options.name);
    lay_out_joint_dofs(joint, q, qd, model);
    q += joint_coord_count(joint.type);
    qd += joint_dof_count(joint.type);
  }
  model.joint_q_start[model.joint_count] = q;
  model.joint_qd_start[model.joint_count] = qd;
  model.articulation_start[model.articulation_count] = model.joint_count;
}

void ModelBuilder::lay_out_joint_dofs(const JointRecord& joint, int q, int qd, Model& model) const {
  for (int k = 0; k < joint_dof_count(joint.type); ++k) {
    const JointDofConfig& dof = joint.dofs.empty() ? joint.options.dof : joint.dofs[k];
    model.joint_armature[qd + k] = dof.armature;
    model.joint_damping[qd + k] = dof.damping;
    model.joint_frictionloss[qd + k] = dof.frictionloss;
    model.joint_stiffness[qd + k] = dof.stiffness;
    model.joint_limit_lower[qd + k] = dof.limit_lower;
    model.joint_limit_upper[qd + k] = dof.limit_upper;
    model.joint_target_ke[qd + k] = dof.target_ke;
    model.joint_target_kd[qd + k] = dof.target_kd;
    std::copy_n(dof.limit_solref.begin(), 2, &model.joint_limit_solref[2 * (qd + k)]);
    std::copy_n(dof.limit_solimp.begin(), 5, &model.joint_limit_solimp[5 * (qd + k)]);
    std::copy_n(dof.friction_solref.begin(), 2, &model.joint_friction_solref[2 * (qd + k)]);
    std::copy_n(dof.friction_solimp.begin(), 5, &model.joint_friction_solimp[5 * (qd + k)]);
  }
  const JointDofConfig& dof = joint.options.dof;
  Scalar* q0 = model.joint_q0.data() + q;  // past the end for a joint without coordinates
  switch (joint.type) {
    case JointType::Revolute:
    case JointType::Prismatic:
      model.joint_q_ref[q] = dof.q_ref;
      q0[0] = dof.q0;
      break;
    case JointType::Ball: q0[3] = model.joint_q_ref[q + 3] = 1; break;
    case JointType::Free:
    case JointType::Distance:
    case JointType::D6:
    case JointType::Cable: {
      // start at the body's pose relative to its parent's as placed: J = X_p^-1 * parent_xform^-1 * body_xform * X_c
      const Transform parent = joint.parent < 0 ? Transform::identity() : body_xform_[joint.parent];
      const Transform J = joint.options.parent_xform.inverse() * parent.inverse() * body_xform_[joint.child] *
                          joint.options.child_xform;
      J.to_array(q0);
      J.to_array(model.joint_q_ref.data() + q);
      break;
    }
    case JointType::Fixed: break;
  }
}

void ModelBuilder::lay_out_bodies(Model& model) const {
  for (int b = 0; b < body_count(); ++b) {
    model.body_mass[b] = body_mass_[b];
    model.body_gravcomp[b] = body_gravcomp_[b];
    Eigen::Map<Vec3>(&model.body_com[3 * b]) = body_com_[b];
    Eigen::Map<Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>>(&model.body_inertia[9 * b]) = body_inertia_[b];
  }
  model.body_name = body_name_;
  model.body_world = body_world_;
  model.shape_world = shape_world_;
}

void ModelBuilder::lay_out_actuators(Model& model) const {
  for (int u = 0; u < actuator_count(); ++u) {
    const ActuatorOptions& a = actuators_[u].options;
    model.actuator_joint[u] = actuators_[u].joint;
    model.actuator_tendon[u] = actuators_[u].tendon;
    model.actuator_body[u] = actuators_[u].body;
    std::copy(actuators_[u].wrench.begin(), actuators_[u].wrench.end(), &model.actuator_wrench[6 * u]);
    model.actuator_gear[u] = a.gear;
    model.actuator_gain[u] = a.gain;
    for (int k = 0; k < 3; ++k) model.actuator_bias[3 * u + k] = a.bias[k];
    model.actuator_ctrl_lower[u] = a.ctrl_lower;
    model.actuator_ctrl_upper[u] = a.ctrl_upper;
    model.actuator_force_lower[u] = a.force_lower;
    model.actuator_force_upper[u] = a.force_upper;
    model.actuator_name.push_back(a.name);
  }
}

Model ModelBuilder::finalize() const {
  int articulation_count = 0;
  const std::vector<JointRecord> joints = articulated_joints(articulation_count);

  Model model;
  model.body_count = body_count();
  model.joint_count = static_cast<int>(joints.size());
  model.shape_count = shape_count();
  model.articulation_count = articulation_count;
  model.actuator_count = actuator_count();
  for (const JointRecord& joint : joints) {
    model.joint_coord_count += joint_coord_count(joint.type);
    model.joint_dof_count += joint_dof_count(joint.type);
  }
  model.gravity = gravity_;
  model.precision = precision_;
  model.timestep = timestep_;
  model.world_count = std::max(world_count_, 1);
  model.allocate();
  for (int w = 0; w < model.world_count; ++w) Eigen::Map<Vec3>(&model.world_gravity[3 * w]) = gravity_;

  lay_out_joints(joints, model);
  lay_out_bodies(model);
  lay_out_shapes(model);
  lay_out_meshes(model);
  lay_out_tendons(model);
  lay_out_actuators(model);
  lay_out_keyframes(model);
  model.collision_filter = collision_filter_;
  model.friction_rule = friction_rule_;
  model.impratio = impratio_;
  model.fluid_density = fluid_density_;
  lay_out_fluid_ellipsoids(model);
  model.fluid_viscosity = fluid_viscosity_;
  model.wind = wind_;
  model.exclude_count = static_cast<int>(excluded_.size());
  model.exclude_shape.clear();
  for (const auto& [a, b] : excluded_) model.exclude_shape.insert(model.exclude_shape.end(), {a, b});
  lay_out_equalities(model);
  lay_out_sensors(model);
  model.check_sizes();
  set_spatial_rest_lengths(model);
  set_invweight0(model);
  model.set_model_id();
  model.index_parameters();
  return model;
}

}  // namespace novaphy
