#include "engine/import/mjcf_import.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>

#include "engine/import/mjcf_translate.h"
#include "engine/import/mujoco_fields.h"
#include "engine/model/error.h"

namespace novaphy {

namespace {

Vec3 vec3(const mjtNum* x) { return Vec3(x[0], x[1], x[2]); }
Quat quat_wxyz(const mjtNum* x) { return Quat(x[0], x[1], x[2], x[3]); }
Transform pose(const mjtNum* pos, const mjtNum* quat_wxyz_) {
  Transform T;
  T.p = vec3(pos);
  T.q = quat_wxyz(quat_wxyz_).normalized();
  return T;
}

// MuJoCo capsules and plane normals run along local Z, NovaPhy's along local Y: rotate Y onto Z
Transform y_to_z() {
  Transform T;
  T.q = Quat(Eigen::AngleAxis<Scalar>(M_PI / 2, Vec3::UnitX()));
  return T;
}

// the sensors NovaPhy computes: MuJoCo 2.2.2's mjtSensor value, its name and NovaPhy's type
struct MujocoSensorType {
  int mj;
  const char* name;
  SensorType type;
};
#define NOVAPHY_MJ_SENSOR(mj, type) \
  { mj, #mj, SensorType::type }
constexpr MujocoSensorType kMujocoSensorTypes[] = {NOVAPHY_MJ_SENSOR(mjSENS_TOUCH, Touch),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_ACCELEROMETER, Accelerometer),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_VELOCIMETER, Velocimeter),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_GYRO, Gyro),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FORCE, Force),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_TORQUE, Torque),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_JOINTPOS, JointPos),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_JOINTVEL, JointVel),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_TENDONPOS, TendonPos),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_TENDONVEL, TendonVel),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_BALLQUAT, BallQuat),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_BALLANGVEL, BallAngVel),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEPOS, FramePos),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEQUAT, FrameQuat),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEXAXIS, FrameXAxis),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEYAXIS, FrameYAxis),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEZAXIS, FrameZAxis),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMELINVEL, FrameLinVel),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEANGVEL, FrameAngVel),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMELINACC, FrameLinAcc),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_FRAMEANGACC, FrameAngAcc),
                                                   NOVAPHY_MJ_SENSOR(mjSENS_SUBTREECOM, SubtreeCom)};
#undef NOVAPHY_MJ_SENSOR

// MuJoCo 2.2.2's sensor types by mjtSensor value, as MJCF names them
constexpr const char* kMujocoSensorNames[mjSENS_USER + 1] = {
    "touch",         "accelerometer", "velocimeter",    "gyro",           "force",          "torque",
    "magnetometer",  "rangefinder",   "jointpos",       "jointvel",       "tendonpos",      "tendonvel",
    "actuatorpos",   "actuatorvel",   "actuatorfrc",    "ballquat",       "ballangvel",     "jointlimitpos",
    "jointlimitvel", "jointlimitfrc", "tendonlimitpos", "tendonlimitvel", "tendonlimitfrc", "framepos",
    "framequat",     "framexaxis",    "frameyaxis",     "framezaxis",     "framelinvel",    "frameangvel",
    "framelinacc",   "frameangacc",   "subtreecom",     "subtreelinvel",  "subtreeangmom",  "clock",
    "user"};

std::optional<SensorType> novaphy_sensor_type(int mj_type) {
  for (const MujocoSensorType& t : kMujocoSensorTypes)
    if (t.mj == mj_type) return t.type;
  return std::nullopt;
}

}  // namespace

class MjcfImporter {
 public:
  MjcfImporter(ModelBuilder& builder, const MujocoFields& m, const ImportOptions& options)
      : builder_(builder), m_(m), options_(options) {
    static_pose_.assign(m_.nbody, options.xform);
  }

  MujocoImport run() {
    out_.body_map.assign(m_.nbody, -1);
    out_.nq = m_.nq;
    out_.nv = m_.nv;
    for (int j = 0; j < m_.njnt; ++j) out_.joints.push_back({m_.jnt_type[j], m_.jnt_qposadr[j], m_.jnt_dofadr[j]});
    for (const auto& joint : builder_.joints_) {
      out_.q_begin += joint_coord_count(joint.type);
      out_.qd_begin += joint_dof_count(joint.type);
    }
    joint_index_.assign(m_.njnt, -1);
    const int joint0 = builder_.joint_count();
    builder_.take_gravity(vec3(m_.gravity), "the file's");
    builder_.take_timestep(m_.timestep);
    for (const int b : body_order()) add_body(b);
    for (int b = 1; b < m_.nbody && m_.body_gravcomp; ++b)
      if (m_.body_gravcomp[b] != 0 && !is_static(b)) builder_.set_body_gravcomp(out_.body_map[b], m_.body_gravcomp[b]);
    builder_.set_collision_filter(CollisionFilter::Mujoco);
    builder_.set_friction_rule(FrictionRule::Mujoco);
    builder_.set_impratio(m_.impratio);
    builder_.set_fluid(m_.density, m_.viscosity, vec3(m_.wind));
    geom_shape_.assign(m_.ngeom, -1);
    for (int g = 0; g < m_.ngeom; ++g) add_geom(g);
    for (int g = 0; g < m_.ngeom && m_.geom_fluid; ++g) add_fluid_ellipsoid(g);
    add_exclusions();
    tendon_index_.assign(m_.ntendon, -1);
    for (int t = 0; t < m_.ntendon; ++t) add_tendon(t);
    out_.actuator_map.assign(m_.nu, -1);
    const int actuator0 = builder_.actuator_count();
    for (int u = 0; u < m_.nu; ++u) add_actuator(u);
    for (int k = 0; k < m_.nkey; ++k) add_keyframe(k, joint0, actuator0);
    for (int e = 0; e < m_.neq; ++e) add_equality(e);
    out_.sensor_map.assign(m_.nsensor, -1);
    for (int i = 0; i < m_.nsensor; ++i) add_sensor(i);
    report_unmodelled();
    return out_;
  }

 private:
  bool is_static(int b) const { return b == 0 || out_.body_map[b] < 0; }

  // MuJoCo's bodies in the order they are added: those welded to the world, then each articulation's subtree in
  // MuJoCo's order, the articulations a fixed tendon joins one after another (a gripper's fingers under a static palm,
  // Robotiq's `split`), so that the builder joins them into one articulation of contiguous joints. Without such a
  // tendon the moving bodies keep MuJoCo's order
  std::vector<int> body_order() const {
    const int n = m_.nbody;
    std::vector<int> root(n, -1);  // a moving body's articulation: its ancestor with joints under a static body
    for (int b = 1; b < n; ++b) {
      const int p = m_.body_parentid[b];
      root[b] = root[p] >= 0 ? root[p] : m_.body_jntnum[b] > 0 ? b : -1;
    }
    std::vector<int> joint_body(m_.njnt), group(n);
    for (int b = 1; b < n; ++b)
      for (int k = 0; k < m_.body_jntnum[b]; ++k) joint_body[m_.body_jntadr[b] + k] = b;
    std::iota(group.begin(), group.end(), 0);
    auto find = [&](int r) {
      while (group[r] != r) r = group[r] = group[group[r]];
      return r;
    };
    for (int t = 0; t < m_.ntendon; ++t)
      for (int w = m_.tendon_adr[t] + 1; w < m_.tendon_adr[t] + m_.tendon_num[t]; ++w) {
        if (m_.wrap_type[w] != mjWRAP_JOINT || m_.wrap_type[w - 1] != mjWRAP_JOINT) continue;
        const int x = find(root[joint_body[m_.wrap_objid[w - 1]]]), y = find(root[joint_body[m_.wrap_objid[w]]]);
        group[std::max(x, y)] = std::min(x, y);
      }
    std::vector<std::vector<int>> subtree(n), roots(n);  // a root's bodies; a group's roots (at its first)
    std::vector<int> order;
    for (int b = 1; b < n; ++b) {
      if (root[b] < 0)
        order.push_back(b);
      else
        subtree[root[b]].push_back(b);
      if (root[b] == b) roots[find(b)].push_back(b);
    }
    for (int g = 1; g < n; ++g)
      for (const int r : roots[g]) order.insert(order.end(), subtree[r].begin(), subtree[r].end());
    return order;
  }

  void add_body(int b) {
    const int p = m_.body_parentid[b];
    const Transform B = pose(m_.body_pos + 3 * b, m_.body_quat + 4 * b);
    const std::string name = m_.name(MjKind::Body, b);
    const RigidBody body = body_inertial(b);
    const int jnt_count = m_.body_jntnum[b];

    if (jnt_count == 0) {
      add_welded_body(b, B, body, name);
      return;
    }

    // one link per joint; the body frame moves through them (MuJoCo's mj_kinematics order)
    int parent = out_.body_map[p];
    const Transform P = is_static(p) ? static_pose_[p] * B : B;
    for (int k = 0; k < jnt_count; ++k) {
      const int j = m_.body_jntadr[b] + k;
      const bool last = k == jnt_count - 1;
      const std::string joint_name = m_.name(MjKind::Joint, j);
      JointOptions options = joint_options(j, joint_name);
      Transform body_xform = Transform::identity();
      const JointType type = joint_frames(j, k, P, joint_name, options, body_xform);

      RigidBody link = body;
      if (!last) link = RigidBody{0, Vec3::Zero(), Mat3::Zero()};
      const std::string link_name = last ? name : name + "/" + joint_name;
      const int child = builder_.add_body_checked(link, body_xform, link_name, true);
      joint_index_[j] = builder_.add_joint(type, parent, child, options);
      out_.joints[j].q = next_q_, out_.joints[j].qd = next_qd_;
      next_q_ += joint_coord_count(type), next_qd_ += joint_dof_count(type);
      parent = child;
    }
    out_.body_map[b] = parent;
  }

  // body b's mass, centre of mass and inertia in its body frame
  RigidBody body_inertial(int b) const {
    RigidBody body;
    body.mass = m_.body_mass[b];
    body.com = vec3(m_.body_ipos + 3 * b);
    const Mat3 R = quat_wxyz(m_.body_iquat + 4 * b).normalized().toRotationMatrix();
    body.inertia = R * vec3(m_.body_inertia + 3 * b).asDiagonal() * R.transpose();
    return body;
  }

  // a body without joints (at B in its parent): static geometry where its parent is static, else a
  // link on a Fixed joint to its parent
  void add_welded_body(int b, const Transform& B, const RigidBody& body, const std::string& name) {
    const int p = m_.body_parentid[b];
    if (is_static(p)) {
      static_pose_[b] = static_pose_[p] * B;
      return;
    }
    const int child = builder_.add_body_checked(body, Transform::identity(), name, true);
    JointOptions options;
    options.parent_xform = B;
    options.name = name + "_weld";
    builder_.add_joint(JointType::Fixed, out_.body_map[p], child, options);
    out_.body_map[b] = child;
  }

  // joint j's name, axis, armature, damping and (hinge and slide) limits
  JointOptions joint_options(int j, const std::string& joint_name) {
    const int da = m_.jnt_dofadr[j];
    JointOptions options;
    options.name = joint_name;
    JointDofConfig& dof = options.dof;
    dof.axis = vec3(m_.jnt_axis + 3 * j);
    dof.armature = m_.dof_armature[da];
    dof.damping = m_.dof_damping[da];
    dof.frictionloss = m_.dof_frictionloss[da];
    dof.friction_solref = solref(m_.dof_solref + mjNREF * da, "joint '" + joint_name + "' solreffriction");
    std::copy_n(m_.dof_solimp + mjNIMP * da, mjNIMP, dof.friction_solimp.begin());
    if (m_.jnt_limited[j] && (m_.jnt_type[j] == mjJNT_HINGE || m_.jnt_type[j] == mjJNT_SLIDE)) {
      dof.limit_lower = m_.jnt_range[2 * j];
      dof.limit_upper = m_.jnt_range[2 * j + 1];
      dof.limit_solref = solref(m_.jnt_solref + mjNREF * j, "joint '" + joint_name + "' solreflimit");
      std::copy_n(m_.jnt_solimp + mjNIMP * j, mjNIMP, dof.limit_solimp.begin());
      if (m_.jnt_margin[j] != 0) warn_motion("joint '" + joint_name + "': a limit's margin is not modelled");
    }
    return options;
  }

  // joint j's type, its frames (the k-th joint of a body whose frame is P in its parent) and a Free
  // joint's initial pose; warns of what it does not model
  JointType joint_frames(int j, int k, const Transform& P, const std::string& joint_name, JointOptions& options,
                         Transform& body_xform) {
    const Vec3 anchor = vec3(m_.jnt_pos + 3 * j);
    const int qa = m_.jnt_qposadr[j];
    JointDofConfig& dof = options.dof;
    JointType type = JointType::Fixed;
    switch (m_.jnt_type[j]) {
      case mjJNT_HINGE:
      case mjJNT_SLIDE: {
        const bool hinge = m_.jnt_type[j] == mjJNT_HINGE;
        type = hinge ? JointType::Revolute : JointType::Prismatic;
        dof.stiffness = m_.jnt_stiffness[j];
        dof.q_ref = m_.qpos_spring[qa];
        dof.q0 = m_.qpos0[qa];  // MuJoCo starts at qpos0 (a joint's ref)
        // MuJoCo moves the joint by qpos - qpos0: fold -qpos0 into the parent joint frame
        Transform ref;
        const Vec3 axis = dof.axis.normalized();
        if (hinge)
          ref.q = Quat(Eigen::AngleAxis<Scalar>(-m_.qpos0[qa], axis));
        else
          ref.p = -m_.qpos0[qa] * axis;
        options.parent_xform = (k == 0 ? P : Transform::identity()) * Transform{anchor} * ref;
        options.child_xform = Transform{anchor};
        break;
      }
      case mjJNT_BALL:
        type = JointType::Ball;
        options.parent_xform = (k == 0 ? P : Transform::identity()) * Transform{anchor};
        options.child_xform = Transform{anchor};
        if (m_.jnt_limited[j]) warn_motion("joint '" + joint_name + "': ball joint limit (cone) is not modelled");
        if (m_.jnt_stiffness[j] != 0) warn_motion("joint '" + joint_name + "': ball joint stiffness is not modelled");
        break;
      case mjJNT_FREE:
        // a free joint places the body frame directly at qpos (MuJoCo ignores its pos)
        type = JointType::Free;
        body_xform = static_pose_[0] * pose(m_.qpos0 + qa, m_.qpos0 + qa + 3);
        if (m_.jnt_stiffness[j] != 0) warn_motion("joint '" + joint_name + "': free joint stiffness is not modelled");
        break;
    }
    return type;
  }

  // geom g as a shape of its body (or static), filtered by its contype and conaffinity (MuJoCo's rule); a
  // geom of a type NovaPhy does not collide is reported unless it is visual only (both zero)
  void add_geom(int g) {
    const int b = m_.geom_bodyid[g];
    const int body = out_.body_map[b];
    if (body < 0 && !options_.static_shapes) return;
    Transform G = pose(m_.geom_pos + 3 * g, m_.geom_quat + 4 * g);
    if (body < 0) G = static_pose_[b] * G;
    const mjtNum* size = m_.geom_size + 3 * g;
    ShapeOptions options;
    options.xform = G;
    options.mu = m_.geom_friction[3 * g];
    options.mu_torsion = m_.geom_friction[3 * g + 1];
    options.mu_rolling = m_.geom_friction[3 * g + 2];
    options.collision_group = m_.geom_contype[g];
    options.collision_mask = m_.geom_conaffinity[g];
    options.priority = m_.geom_priority[g];
    options.condim = m_.geom_condim[g];
    options.name = m_.name(MjKind::Geom, g);
    options.solref = solref(m_.geom_solref + mjNREF * g, "geom '" + m_.name(MjKind::Geom, g) + "' solref");
    std::copy_n(m_.geom_solimp + mjNIMP * g, 5, options.solimp.begin());
    options.solmix = m_.geom_solmix[g];
    options.margin = m_.geom_margin[g];
    options.gap = m_.geom_gap[g];
    ShapeOptions along_z = options;  // capsules and plane normals: MuJoCo's Z onto NovaPhy's Y
    along_z.xform = G * y_to_z();
    switch (m_.geom_type[g]) {
      case mjGEOM_PLANE: geom_shape_[g] = builder_.add_shape(ShapeType::Plane, body, Vec3::Ones(), along_z); break;
      case mjGEOM_SPHERE: geom_shape_[g] = builder_.add_shape_sphere(body, size[0], options); break;
      case mjGEOM_CAPSULE: geom_shape_[g] = builder_.add_shape_capsule(body, size[0], size[1], along_z); break;
      case mjGEOM_BOX: geom_shape_[g] = builder_.add_shape_box(body, vec3(size), options); break;
      case mjGEOM_CYLINDER: geom_shape_[g] = builder_.add_shape_cylinder(body, size[0], size[1], along_z); break;
      case mjGEOM_ELLIPSOID: geom_shape_[g] = builder_.add_shape_ellipsoid(body, vec3(size), options); break;
      case mjGEOM_MESH:  // (a visual mesh is left out: only its mass counts)
        if (options.collision_group != 0 || options.collision_mask != 0)
          geom_shape_[g] = builder_.add_shape_mesh(body, mesh(g), options);
        break;
      default:
        if (m_.geom_contype[g] != 0 || m_.geom_conaffinity[g] != 0)
          warn_motion("geom '" + m_.name(MjKind::Geom, g) + "' of type " + std::to_string(m_.geom_type[g]) +
                      (m_.geom_type[g] == mjGEOM_HFIELD ? " (height field)" : " (MuJoCo >= 3's SDF or later)") +
                      " is not modelled for collision; its mass is kept");
    }
  }

  // geom g's mesh as a builder mesh (each MuJoCo mesh once); its vertices are in the geom's frame
  int mesh(int g) {
    const int id = m_.geom_dataid[g];
    if (const auto it = mesh_index_.find(id); it != mesh_index_.end()) return it->second;
    std::vector<Vec3> vertices(m_.mesh_vertnum[id]);
    const float* v = m_.mesh_vert + 3 * static_cast<size_t>(m_.mesh_vertadr[id]);
    for (Vec3& x : vertices) x = Vec3(v[0], v[1], v[2]), v += 3;
    const std::string name = "geom '" + m_.name(MjKind::Geom, g) + "' (mesh '" + m_.name(MjKind::Mesh, id) + "')";
    return mesh_index_[id] = builder_.add_mesh(vertices, name);
  }

  // MuJoCo's <exclude> body pairs as pairs of their geoms' shapes
  void add_exclusions() {
    for (int e = 0; e < m_.nexclude; ++e) {
      const int body1 = (m_.exclude_signature[e] >> 16) - m_.exclude_body_offset;
      const int body2 = (m_.exclude_signature[e] & 0xffff) - m_.exclude_body_offset;
      for (int a = 0; a < m_.ngeom; ++a)
        for (int b = 0; b < m_.ngeom; ++b)
          if (m_.geom_bodyid[a] == body1 && m_.geom_bodyid[b] == body2 && geom_shape_[a] >= 0 && geom_shape_[b] >= 0)
            builder_.exclude_shapes(geom_shape_[a], geom_shape_[b]);
    }
  }

  // a geom of fluidshape "ellipsoid" on a moving body: MuJoCo's ellipsoid fluid model, its compiled coefficients
  // (geom_fluid: interaction, blunt, slender and angular drag, Kutta and Magnus lift, virtual mass and inertia)
  void add_fluid_ellipsoid(int g) {
    const double* fluid = m_.geom_fluid + 12 * g;
    const int b = m_.geom_bodyid[g];
    if (!(fluid[0] > 0) || is_static(b)) return;
    const double* size = m_.geom_size + 3 * g;
    Vec3 semi_axes(size[0], size[1], size[2]);
    if (m_.geom_type[g] == mjGEOM_SPHERE) semi_axes = Vec3::Constant(size[0]);
    if (m_.geom_type[g] == mjGEOM_CAPSULE) semi_axes = Vec3(size[0], size[0], size[1] + size[0]);
    if (m_.geom_type[g] == mjGEOM_CYLINDER) semi_axes = Vec3(size[0], size[0], size[1]);
    FluidEllipsoidOptions options;
    options.blunt_drag = fluid[1], options.slender_drag = fluid[2], options.angular_drag = fluid[3];
    options.kutta_lift = fluid[4], options.magnus_lift = fluid[5];
    options.added_mass = vec3(fluid + 6);
    options.added_inertia = vec3(fluid + 9);
    builder_.add_fluid_ellipsoid(out_.body_map[b], pose(m_.geom_pos + 3 * g, m_.geom_quat + 4 * g), semi_axes, options);
  }

  // a fixed tendon over hinges and slides, or a spatial one through sites around spheres and cylinders (model.h); a
  // fixed one over other joints is reported
  void add_tendon(int t) {
    const std::string name = m_.name(MjKind::Tendon, t);
    const TendonOptions options = tendon_options(t, name);
    const int begin = m_.tendon_adr[t], end = begin + m_.tendon_num[t];
    if (begin < end && m_.wrap_type[begin] != mjWRAP_JOINT) {
      tendon_index_[t] = builder_.add_spatial_tendon(tendon_path(begin, end), options);
      return;
    }
    std::vector<int> joints;
    std::vector<Scalar> coefs;
    for (int w = begin; w < end; ++w) {
      const int j = m_.wrap_objid[w];
      if (m_.jnt_type[j] != mjJNT_HINGE && m_.jnt_type[j] != mjJNT_SLIDE) {
        warn_motion("tendon '" + name +
                    "' spans a ball or free joint (fixed tendons over hinges and slides only): " + "not modelled");
        return;
      }
      joints.push_back(joint_index_[j]);
      coefs.push_back(m_.wrap_prm[w]);
    }
    tendon_index_[t] = builder_.add_tendon(joints, coefs, options);
  }

  // a spatial tendon's path: its sites, the geoms it wraps around (with their side sites) and its pulleys, each on
  // its body (a static body's in the world)
  std::vector<TendonPathElement> tendon_path(int begin, int end) const {
    std::vector<TendonPathElement> path;
    auto on = [&](TendonPathKind kind, int body, const Transform& local, Scalar size) {
      path.push_back({kind, is_static(body) ? -1 : out_.body_map[body],
                      is_static(body) ? static_pose_[body] * local : local, size});
    };
    auto site = [&](TendonPathKind kind, int i) {
      on(kind, m_.site_bodyid[i], pose(m_.site_pos + 3 * i, m_.site_quat + 4 * i), 0);
    };
    for (int w = begin; w < end; ++w) {
      const int id = m_.wrap_objid[w];
      switch (m_.wrap_type[w]) {
        case mjWRAP_SITE: site(TendonPathKind::Site, id); break;
        case mjWRAP_PULLEY: path.push_back({TendonPathKind::Pulley, -1, Transform::identity(), m_.wrap_prm[w]}); break;
        default: {  // (a sphere or a cylinder: a joint's wrap is a fixed tendon's)
          const auto kind = m_.wrap_type[w] == mjWRAP_SPHERE ? TendonPathKind::Sphere : TendonPathKind::Cylinder;
          on(kind, m_.geom_bodyid[id], pose(m_.geom_pos + 3 * id, m_.geom_quat + 4 * id), m_.geom_size[3 * id]);
          const int side = static_cast<int>(std::lround(m_.wrap_prm[w]));
          if (side >= 0) site(TendonPathKind::SideSite, side);
        }
      }
    }
    return path;
  }

  // a tendon's spring, damper, limits and dry friction, as MuJoCo's (what is not modelled reported)
  TendonOptions tendon_options(int t, const std::string& name) {
    TendonOptions options;
    options.stiffness = m_.tendon_stiffness[t];
    options.damping = m_.tendon_damping[t];
    const double* spring = m_.tendon_lengthspring + m_.tendon_lengthspring_width * t;
    if (m_.tendon_lengthspring_width == 2 && spring[1] != spring[0] && m_.tendon_stiffness[t] != 0)
      warn_motion("tendon '" + name + "': a spring of a dead band (springlength, two values) is not modelled");
    options.rest_length = spring[0];
    if (m_.tendon_armature && m_.tendon_armature[t] != 0)
      warn_motion("tendon '" + name + "': armature is not modelled");
    if (m_.tendon_limited[t]) {
      options.limit_lower = m_.tendon_range[2 * t];
      options.limit_upper = m_.tendon_range[2 * t + 1];
      options.limit_solref = solref(m_.tendon_solref_lim + mjNREF * t, "tendon '" + name + "' solreflimit");
      std::copy_n(m_.tendon_solimp_lim + mjNIMP * t, mjNIMP, options.limit_solimp.begin());
      if (m_.tendon_margin[t] != 0) warn_motion("tendon '" + name + "': a limit's margin is not modelled");
    }
    options.frictionloss = m_.tendon_frictionloss[t];
    options.friction_solref = solref(m_.tendon_solref_fri + mjNREF * t, "tendon '" + name + "' solreffriction");
    std::copy_n(m_.tendon_solimp_fri + mjNIMP * t, mjNIMP, options.friction_solimp.begin());
    options.name = name;
    return options;
  }

  // MuJoCo's affine actuators (motor, position, velocity, general of fixed gain and affine or no bias) on a
  // hinge, slide or fixed tendon without activation dynamics (engine/model/actuator.h); any other is reported
  void add_actuator(int u) {
    const std::string name = m_.name(MjKind::Actuator, u);
    if (m_.actuator_plugin && m_.actuator_plugin[u] >= 0) {
      const int p = m_.actuator_plugin[u];
      const std::string instance = m_.name(MjKind::Plugin, p);
      fail("actuator '", name, "': its force comes from engine plugin instance ", p,
           instance[0] == '#' ? "" : " '" + instance + "'",
           ", and NovaPhy does not run MuJoCo's engine plugins (mujoco.pid and others): not imported");
    }
    const std::string unsupported = unsupported_actuator(u);
    if (!unsupported.empty()) {
      warn_motion("actuator '" + name + "' " + unsupported + ": not modelled");
      return;
    }
    constexpr Scalar inf = std::numeric_limits<Scalar>::infinity();
    const bool ctrl_limited = m_.actuator_ctrllimited[u] && m_.clamp_ctrl;
    const bool force_limited = m_.actuator_forcelimited[u];
    ActuatorOptions a;
    a.gear = m_.actuator_gear[6 * u];
    a.gain = m_.actuator_gainprm[mjNGAIN * u];
    if (m_.actuator_biastype[u] == mjBIAS_AFFINE) a.bias = vec3(m_.actuator_biasprm + mjNBIAS * u);
    a.ctrl_lower = ctrl_limited ? m_.actuator_ctrlrange[2 * u] : -inf;
    a.ctrl_upper = ctrl_limited ? m_.actuator_ctrlrange[2 * u + 1] : inf;
    a.force_lower = force_limited ? m_.actuator_forcerange[2 * u] : -inf;
    a.force_upper = force_limited ? m_.actuator_forcerange[2 * u + 1] : inf;
    joint_force_range(u, name, a);
    if (m_.actuator_damping && m_.actuator_damping[u] != 0)
      warn_motion("actuator '" + name + "': damping is not modelled");
    if (m_.actuator_armature && m_.actuator_armature[u] != 0)
      warn_motion("actuator '" + name + "': armature is not modelled");
    a.name = name;
    const int target = m_.actuator_trnid[2 * u];
    if (m_.actuator_trntype[u] == mjTRN_SITE) {
      std::array<Scalar, 6> gear;
      std::copy_n(m_.actuator_gear + 6 * u, 6, gear.begin());
      a.gear = 1;
      out_.actuator_map[u] = builder_.add_site_actuator(
          out_.body_map[m_.site_bodyid[target]], pose(m_.site_pos + 3 * target, m_.site_quat + 4 * target), gear, a);
      return;
    }
    out_.actuator_map[u] = m_.actuator_trntype[u] == mjTRN_TENDON
                               ? builder_.add_tendon_actuator(tendon_index_[target], a)
                               : builder_.add_actuator(joint_index_[target], a);
  }

  // MuJoCo >= 3's limit on the total actuator force of the joint actuator u drives (jnt_actfrcrange), as the
  // translation gives it to 2.2.2 (engine/import/mjcf_translate.h): the force range of the joint's one actuator
  void joint_force_range(int u, const std::string& name, ActuatorOptions& a) const {
    if (!m_.jnt_actfrclimited || m_.actuator_trntype[u] != mjTRN_JOINT) return;
    const int j = m_.actuator_trnid[2 * u];
    if (!m_.jnt_actfrclimited[j]) return;
    for (int v = 0; v < m_.nu; ++v)
      if (v != u && m_.actuator_trntype[v] == mjTRN_JOINT && m_.actuator_trnid[2 * v] == j)
        fail("actuator '", name, "': joint '", m_.name(MjKind::Joint, j),
             "' limits the force of its several actuators together (actuatorfrcrange): not modelled");
    narrow_force_range(m_.jnt_actfrcrange[2 * j], m_.jnt_actfrcrange[2 * j + 1], a.gear, &a.force_lower,
                       &a.force_upper);
  }

  // keyframe k over the joints and actuators this import added (from joint0 and actuator0): qpos and qvel
  // in NovaPhy's coordinates, the commands of the actuators imported
  void add_keyframe(int k, int joint0, int actuator0) {
    std::vector<Scalar> q(out_.q_begin + m_.nq), qd(out_.qd_begin + m_.nv);
    out_.to_joint_q(m_.key_qpos + k * m_.nq, q.data());
    out_.to_joint_qd(m_.key_qpos + k * m_.nq, m_.key_qvel + k * m_.nv, qd.data());
    std::vector<Scalar> ctrl(builder_.actuator_count() - actuator0);
    for (int u = 0; u < m_.nu; ++u)
      if (out_.actuator_map[u] >= 0) ctrl[out_.actuator_map[u] - actuator0] = m_.key_ctrl[k * m_.nu + u];
    builder_.keyframes_.push_back({m_.name(MjKind::Key, k), joint0, builder_.joint_count(), actuator0,
                                   std::vector<Scalar>(q.begin() + out_.q_begin, q.end()),
                                   std::vector<Scalar>(qd.begin() + out_.qd_begin, qd.end()), ctrl});
  }

  // why actuator u is not one NovaPhy models ("" when it is)
  std::string unsupported_actuator(int u) const {
    const int target = m_.actuator_trnid[2 * u];
    if (m_.actuator_trntype[u] == mjTRN_TENDON) {
      if (tendon_index_[target] < 0) return "drives tendon '" + m_.name(MjKind::Tendon, target) + "', not modelled";
    } else if (m_.actuator_trntype[u] == mjTRN_SITE) {
      if (m_.actuator_trnid[2 * u + 1] >= 0) return "drives a site relative to a reference site (refsite)";
      if (is_static(m_.site_bodyid[target])) return "drives a site on a body that does not move";
      if (m_.actuator_biastype[u] == mjBIAS_AFFINE && m_.actuator_biasprm[mjNBIAS * u + 2] != 0)
        return "drives a site with a force on the site's velocity (biasprm[2])";
    } else if (m_.actuator_trntype[u] != mjTRN_JOINT) {
      return "drives a body or a slider-crank (joints, fixed tendons and sites only are modelled)";
    } else if (m_.jnt_type[target] != mjJNT_HINGE && m_.jnt_type[target] != mjJNT_SLIDE) {
      return "drives a ball or free joint (hinges and slides only)";
    }
    if (m_.actuator_dyntype[u] != mjDYN_NONE) return "has activation dynamics (dyntype)";
    if (m_.actuator_gaintype[u] != mjGAIN_FIXED) return "has a gain that is not fixed (gaintype)";
    if (m_.actuator_biastype[u] != mjBIAS_NONE && m_.actuator_biastype[u] != mjBIAS_AFFINE)
      return "has a bias that is not affine (biastype)";
    return "";
  }

  // MuJoCo's connect, weld and joint equalities, the active ones (model.h); tendon and distance are reported
  void add_equality(int e) {
    const std::string name = m_.name(MjKind::Equality, e);
    const mjtNum* data = m_.eq_data + m_.eq_data_width * e;
    if (!m_.eq_active[e]) return;
    const int id1 = m_.eq_obj1id[e], id2 = m_.eq_obj2id[e];
    if (m_.eq_objtype && (m_.eq_type[e] == mjEQ_CONNECT || m_.eq_type[e] == mjEQ_WELD) &&
        m_.eq_objtype[e] != mjOBJ_BODY) {
      warn_motion("equality constraint '" + name + "' joins sites (bodies only are modelled): not modelled");
      return;
    }
    switch (m_.eq_type[e]) {
      case mjEQ_CONNECT: {
        // a body welded to the world is the world, its anchor moved into the world frame
        Vec3 anchor[2] = {vec3(data), vec3(data + 3)};
        int body[2] = {id1, id2 < 0 ? 0 : id2};
        for (int k = 0; k < 2; ++k)
          if (is_static(body[k])) {
            anchor[k] = static_pose_[body[k]].apply(anchor[k]);
            body[k] = -1;
          } else {
            body[k] = out_.body_map[body[k]];
          }
        if (body[0] < 0) {
          std::swap(body[0], body[1]);
          std::swap(anchor[0], anchor[1]);
        }
        if (body[0] < 0) return;  // two static bodies: nothing moves
        soften_equality(e, builder_.add_connect(body[0], body[1], anchor[0], name, anchor[1]));
        break;
      }
      case mjEQ_JOINT: {
        std::array<Scalar, 5> poly;
        std::copy_n(data, 5, poly.begin());
        soften_equality(e,
                        builder_.add_joint_coupling(joint_index_[id1], id2 < 0 ? -1 : joint_index_[id2], poly, name));
        break;
      }
      case mjEQ_WELD: add_weld(e, name); break;
      default: warn_motion("equality constraint '" + name + "' (tendon or distance) is not modelled");
    }
  }

  // MuJoCo equality e's softness on the builder's equality `added`
  void soften_equality(int e, int added) {
    std::array<Scalar, mjNIMP> solimp;
    std::copy_n(m_.eq_solimp + mjNIMP * e, mjNIMP, solimp.begin());
    builder_.set_equality_softness(
        added, solref(m_.eq_solref + mjNREF * e, "equality constraint '" + m_.name(MjKind::Equality, e) + "' solref"),
        solimp);
  }

  // a solref as MuJoCo steps it: one that mixes its two formats (one number > 0, the other not) is MuJoCo's default
  // (0.02, 1), which MuJoCo puts in its place with a warning each step
  std::array<Scalar, 2> solref(const double* x, const std::string& who) {
    if ((x[0] > 0) == (x[1] > 0)) return {x[0], x[1]};
    out_.warnings.push_back(
        who + " (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) +
        ") mixes MuJoCo's two formats: MuJoCo's default (0.02, 1) in its place, as MuJoCo steps it");
    return {0.02, 1};
  }

  // a weld: MuJoCo's data hold body2's anchor (its frame), that anchor in body1's frame and body2's orientation
  // in body1's; a body welded to the world stands for the world, the held pose moved accordingly
  void add_weld(int e, const std::string& name) {
    const mjtNum* data = m_.eq_data + m_.eq_data_width * e;
    if (data[10] == 0) {
      warn_motion("equality constraint '" + name + "': a weld of torquescale 0 is not modelled");
      return;
    }
    if (data[10] != 1 && (m_.eq_solref[mjNREF * e] != 0 || m_.eq_solref[mjNREF * e + 1] != 0))
      warn_motion("equality constraint '" + name + "': a soft weld's torquescale other than 1 is not modelled (1)");
    const int id1 = m_.eq_obj1id[e], id2 = m_.eq_obj2id[e] < 0 ? 0 : m_.eq_obj2id[e];
    Transform relative;
    relative.q = quat_wxyz(data + 6).normalized();
    relative.p = vec3(data + 3) - relative.q * vec3(data);
    Vec3 anchor = vec3(data);
    if (is_static(id1)) relative = static_pose_[id1] * relative;
    if (is_static(id2)) {
      relative = relative * static_pose_[id2].inverse();
      anchor = static_pose_[id2].apply(anchor);
    }
    const int body1 = is_static(id1) ? -1 : out_.body_map[id1], body2 = is_static(id2) ? -1 : out_.body_map[id2];
    if (body1 < 0 && body2 < 0) return;  // two static bodies: nothing moves
    soften_equality(e, builder_.add_weld(body1, body2, name, anchor, relative));
  }

  // sensor i as the builder's sensor of its type, on its object's NovaPhy body (or joint, tendon), its frame the
  // site's, the geom's or the body's (inertial frame for a body, MuJoCo's mjOBJ_BODY); one NovaPhy does not compute
  // is reported
  void add_sensor(int i) {
    const std::string name = m_.name(MjKind::Sensor, i);
    const int mj_type = m_.sensor_type[i], objtype = m_.sensor_objtype[i], id = m_.sensor_objid[i];
    const std::string type_name = m_.sensor_type_name ? m_.sensor_type_name[i]
                                  : mj_type >= 0      ? kMujocoSensorNames[mj_type]
                                                      : "unknown";
    const auto skip = [&](const std::string& why) {
      out_.warnings.push_back("sensor '" + name + "' (" + type_name + "): " + why + "; it is not computed");
    };
    const std::optional<SensorType> type = novaphy_sensor_type(mj_type);
    if (!type) return skip("NovaPhy has no sensor of this type");
    const bool frame = *type >= SensorType::FramePos && *type <= SensorType::FrameAngAcc;
    if (frame && m_.sensor_refid[i] >= 0) return skip("a frame sensor relative to another object's frame");
    SensorOptions options;
    options.name = name;
    options.cutoff = m_.sensor_cutoff[i];
    int object = -1;
    switch (sensor_object_kind(*type)) {
      case SensorObject::Joint: object = joint_index_[id]; break;
      case SensorObject::Tendon:
        object = tendon_index_[id];
        if (object < 0) return skip("its tendon is not modelled");
        break;
      case SensorObject::Body: {
        int body = id;
        Transform local;
        if (objtype == mjOBJ_SITE) {
          body = m_.site_bodyid[id];
          local = pose(m_.site_pos + 3 * id, m_.site_quat + 4 * id);
          if (*type == SensorType::Touch) {
            const int site_type = m_.site_type[id];
            const std::pair<int, ShapeType> zones[] = {{mjGEOM_SPHERE, ShapeType::Sphere},
                                                       {mjGEOM_CAPSULE, ShapeType::Capsule},
                                                       {mjGEOM_ELLIPSOID, ShapeType::Ellipsoid},
                                                       {mjGEOM_CYLINDER, ShapeType::Cylinder},
                                                       {mjGEOM_BOX, ShapeType::Box}};
            for (const auto& [mj, zone] : zones)
              if (site_type == mj) options.zone_type = static_cast<int>(zone);
            if (options.zone_type < 0) return skip("its site's type has no volume");
            options.zone_size = vec3(m_.site_size + 3 * id);
          }
        } else if (objtype == mjOBJ_GEOM) {
          body = m_.geom_bodyid[id];
          local = pose(m_.geom_pos + 3 * id, m_.geom_quat + 4 * id);
        } else if (objtype == mjOBJ_BODY) {
          local = pose(m_.body_ipos + 3 * id, m_.body_iquat + 4 * id);
        } else if (objtype != mjOBJ_XBODY) {
          return skip("it is attached to an object that is not a body, geom or site");
        }
        if (is_static(body)) {
          if (*type == SensorType::Touch || *type == SensorType::SubtreeCom)
            return skip("its body does not move (a static body)");
          local = static_pose_[body] * local;
        } else {
          object = out_.body_map[body];
        }
        options.xform = local;
        break;
      }
    }
    out_.sensor_map[i] = builder_.add_sensor(*type, object, options);
  }

  // what the import left out that changes the motion (sensors, cameras and lights do not)
  void report_unmodelled() {
    for (int j = 0; j < m_.njnt && m_.jnt_actgravcomp && m_.jnt_actfrclimited; ++j)
      if (m_.jnt_actgravcomp[j] && m_.jnt_actfrclimited[j])
        warn_motion("joint '" + m_.name(MjKind::Joint, j) +
                    "': actuatorgravcomp under an actuatorfrcrange (the compensation is not clamped by the range)");
    if (m_.nflex > 0) warn_motion(std::to_string(m_.nflex) + " flex object(s) (deformables) are not modelled");
    if (m_.nplugin > 0) warn_motion(std::to_string(m_.nplugin) + " engine plugin instance(s) are not modelled");
    if (!m_.filter_parent)
      warn_motion("the contact filter's parent rule is disabled (<flag filterparent=\"disable\">): NovaPhy keeps it");
    if (m_.npair > 0) warn_motion(std::to_string(m_.npair) + " explicit contact pair(s) are not modelled");
    for (int g = 0; g < m_.ngeom && m_.geom_fluid; ++g)
      if (m_.geom_fluid[12 * g] > 0 && m_.geom_fluid[12 * g] != 1)
        warn_motion("geom '" + m_.name(MjKind::Geom, g) + "': an ellipsoid fluid interaction scaled by " +
                    std::to_string(m_.geom_fluid[12 * g]) + " is modelled unscaled");
  }

  // a report entry for something left out that changes the motion
  void warn_motion(const std::string& message) { out_.warnings.push_back(message + " (affects motion)"); }

  ModelBuilder& builder_;
  const MujocoFields& m_;
  int next_q_ = 0, next_qd_ = 0;  // the next joint's first coordinate and dof (MujocoJoint::q, qd)
  ImportOptions options_;
  MujocoImport out_;
  std::vector<Transform> static_pose_;  // world pose of bodies welded to the world
  std::vector<int> joint_index_;        // MuJoCo joint -> NovaPhy joint
  std::vector<int> geom_shape_;         // MuJoCo geom -> NovaPhy shape (-1: none)
  std::map<int, int> mesh_index_;       // MuJoCo mesh -> builder mesh
  std::vector<int> tendon_index_;       // MuJoCo tendon -> NovaPhy tendon (-1: not modelled)
};

int mujoco_sensor_type(const std::string& name) {
  for (const MujocoSensorType& t : kMujocoSensorTypes)
    if (name == t.name) return t.mj;
  return -1;
}

mjModel* load_mujoco_model(const std::string& path, std::vector<double>* body_gravcomp) {
  if (!std::filesystem::exists(path)) fail("cannot load '", path, "': file does not exist");
  char error[1024] = "";
  // MJCF of MuJoCo >= 3 translated for 2.2.2's parser (engine/import/mjcf_translate.h); URDF as it is
  const bool urdf = std::filesystem::path(path).extension() == ".urdf";
  if (urdf) check_urdf(path);
  const TranslatedMjcf translated = urdf ? TranslatedMjcf{} : translate_mjcf(path);
  mjModel* m = mj_loadXML(path.c_str(), translated.vfs.get(), error, sizeof(error));
  if (m == nullptr) fail("cannot load '", path, "': ", error);
  try {
    apply_translation(m, translated);
    if (body_gravcomp) *body_gravcomp = translated_gravcomp(m, translated);
  } catch (const Error& e) {
    mj_deleteModel(m);
    fail("cannot load '", path, "': ", e.what());
  }
  return m;
}

MujocoImport import_mujoco_fields(ModelBuilder& builder, const MujocoFields& m, const ImportOptions& options) {
  check_mujoco_fields(m);
  return MjcfImporter(builder, m, options).run();
}

MujocoImport import_mujoco_model(ModelBuilder& builder, const mjModel* m, const ImportOptions& options) {
  return import_mujoco_fields(builder, mujoco_fields(m), options);
}

MujocoImport import_mjcf(ModelBuilder& builder, const std::string& path, const ImportOptions& options) {
  std::vector<double> body_gravcomp;
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(path, &body_gravcomp), mj_deleteModel);
  MujocoFields fields = mujoco_fields(m.get());
  if (!body_gravcomp.empty()) fields.body_gravcomp = body_gravcomp.data();
  return import_mujoco_fields(builder, fields, options);
}

std::vector<std::string> ModelBuilder::add_mjcf(const std::string& path, const ImportOptions& options) {
  return import_mjcf(*this, path, options).warnings;
}

void MujocoImport::to_joint_q(const mjtNum* qpos, Scalar* joint_q) const {
  for (const MujocoJoint& j : joints) {
    const mjtNum* x = qpos + j.qposadr;
    Scalar* q = joint_q + q_begin + j.q;
    switch (j.type) {
      case mjJNT_HINGE:
      case mjJNT_SLIDE: q[0] = x[0]; break;
      case mjJNT_BALL: q[0] = x[1], q[1] = x[2], q[2] = x[3], q[3] = x[0]; break;
      case mjJNT_FREE: pose(x, x + 3).to_array(q); break;
    }
  }
}

void MujocoImport::to_qpos(const Scalar* joint_q, mjtNum* qpos) const {
  for (const MujocoJoint& j : joints) {
    mjtNum* x = qpos + j.qposadr;
    const Scalar* q = joint_q + q_begin + j.q;
    switch (j.type) {
      case mjJNT_HINGE:
      case mjJNT_SLIDE: x[0] = q[0]; break;
      case mjJNT_BALL:  // NovaPhy [x y z w], MuJoCo [w x y z]; Free: position, then the same
      case mjJNT_FREE: {
        const int p = j.type == mjJNT_FREE ? 3 : 0;
        std::copy_n(q, p, x);
        x[p] = q[p + 3];
        std::copy_n(q + p, 3, x + p + 1);
        break;
      }
    }
  }
}

void MujocoImport::to_joint_qd(const mjtNum* qpos, const mjtNum* qvel, Scalar* joint_qd) const {
  Eigen::Map<VecX>(joint_qd + qd_begin, nv) = velocity_map(qpos) * Eigen::Map<const VecX>(qvel, nv);
}

void MujocoImport::to_qvel(const mjtNum* qpos, const Scalar* joint_qd, mjtNum* qvel) const {
  // the map's inverse is its transpose: a permutation, each free joint's block orthogonal
  Eigen::Map<VecX>(qvel, nv) = velocity_map(qpos).transpose() * Eigen::Map<const VecX>(joint_qd + qd_begin, nv);
}

MatX MujocoImport::velocity_map(const mjtNum* qpos) const {
  // NovaPhy's dof j.qd + k is MuJoCo's j.dofadr + k, but a Free joint's
  MatX T = MatX::Zero(nv, nv);
  for (const MujocoJoint& j : joints) {
    const int d = j.dofadr, e = j.qd;
    if (j.type != mjJNT_FREE) {
      for (int k = 0; k < (j.type == mjJNT_BALL ? 3 : 1); ++k) T(e + k, d + k) = 1;
      continue;
    }
    const Mat3 R = quat_wxyz(qpos + j.qposadr + 3).normalized().toRotationMatrix();
    // [w_world; v] = [0 R; I 0] [v; w_body]
    T.block(e, d + 3, 3, 3) = R;
    T.block(e + 3, d, 3, 3).setIdentity();
  }
  return T;
}

}  // namespace novaphy
