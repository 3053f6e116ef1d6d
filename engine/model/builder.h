// ModelBuilder: the seed's scene-construction API. Every call checks its arguments and throws
// Error naming the item; finalize() lays the scene out as a Model.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/model/model.h"
#include "kernels/hull.h"

namespace novaphy {

struct RigidBody {
  Scalar mass = 1;
  Vec3 com = Vec3::Zero();
  Mat3 inertia = Mat3::Identity();  // about the centre of mass, body frame

  static RigidBody from_box(Scalar mass, const Vec3& half_extents);
  static RigidBody from_sphere(Scalar mass, Scalar radius);
  // capsule along the body's local Y axis: radius and half height of the cylinder part
  static RigidBody from_capsule(Scalar mass, Scalar radius, Scalar half_height);
};

struct JointDofConfig {
  Vec3 axis = Vec3(1, 0, 0);
  Scalar limit_lower = -std::numeric_limits<Scalar>::infinity();
  Scalar limit_upper = std::numeric_limits<Scalar>::infinity();
  Scalar armature = 0;
  Scalar damping = 0;
  Scalar frictionloss = 0;  // dry friction: each dof's generalised friction force at most this either way
  Scalar stiffness = 0;     // spring towards q_ref, Revolute and Prismatic joints
  Scalar q_ref = 0;
  Scalar q0 = 0;         // initial coordinate, Revolute and Prismatic joints (model.joint_q0)
  Scalar target_ke = 0;  // PD drive gains (Control.joint_target_ke/kd start here)
  Scalar target_kd = 0;
  // the softness of its limits' rows and of its dry friction's row, MuJoCo's solreflimit / solimplimit and
  // solreffriction / solimpfriction (model.h, engine/solver/parts/soft_row.h): solref (0, 0) a hard row (the
  // solver's erp and slop), else (time constant > 0, damping ratio > 0) or (-stiffness < 0, -damping <= 0)
  std::array<Scalar, 2> limit_solref = {0, 0};
  std::array<Scalar, 5> limit_solimp = {0.9, 0.95, 0.001, 0.5, 2};  // dmin, dmax, width, midpoint, power
  std::array<Scalar, 2> friction_solref = {0, 0};
  std::array<Scalar, 5> friction_solimp = {0.9, 0.95, 0.001, 0.5, 2};
};

// shapes collide when (group_a & mask_b) != 0 and (group_b & mask_a) != 0
struct ShapeOptions {
  Transform xform;  // body frame -> shape frame
  Scalar mu = 0.5;
  Scalar restitution = 0;
  int collision_group = 1;
  int collision_mask = -1;
  int priority = 0;  // FrictionRule::Mujoco: the shape of higher priority decides a contact's friction and condim
  int condim = 3;    // MuJoCo's: 1 frictionless, 3 sliding friction, 4 and torsional, 6 and rolling
  Scalar mu_torsion = 0.005, mu_rolling = 0.0001;  // (m) the torsional and rolling friction of condim 4 and 6
  // MuJoCo's contact softness (model.h, engine/solver/parts/contact_softness.h): solref (0, 0) is a rigid contact (the
  // solver's erp and slop); (time constant > 0, damping ratio > 0) or (-stiffness < 0, -damping <= 0) a soft one. A
  // pair of equal priority mixes its shapes' as MuJoCo does, which leaves it rigid where one of them is
  std::array<Scalar, 2> solref = {0, 0};
  std::array<Scalar, 5> solimp = {0.9, 0.95, 0.001, 0.5, 2};  // dmin, dmax, width, midpoint, power
  Scalar solmix = 1;
  Scalar margin = 0;  // a soft contact is active from this distance, less gap
  Scalar gap = 0;
  std::string name;
};

// an actuator's parameters (add_actuator); the defaults make a motor of unit gear, unlimited
struct ActuatorOptions {
  Scalar gear = 1;
  Scalar gain = 1;
  Vec3 bias = Vec3::Zero();
  Scalar ctrl_lower = -std::numeric_limits<Scalar>::infinity(), ctrl_upper = std::numeric_limits<Scalar>::infinity();
  Scalar force_lower = -std::numeric_limits<Scalar>::infinity(), force_upper = std::numeric_limits<Scalar>::infinity();
  std::string name;

  // a motor's options: unit gain, no bias
  static ActuatorOptions motor(Scalar gear, Scalar ctrl_lower, Scalar ctrl_upper, Scalar force_lower,
                               Scalar force_upper, const std::string& name) {
    ActuatorOptions a;
    a.gear = gear, a.ctrl_lower = ctrl_lower, a.ctrl_upper = ctrl_upper;
    a.force_lower = force_lower, a.force_upper = force_upper, a.name = name;
    return a;
  }
};

// a tendon's parameters (add_tendon, add_spatial_tendon): a spring and damper along it, its range and its dry friction
struct TendonOptions {
  Scalar stiffness = 0, damping = 0;
  Scalar rest_length = std::numeric_limits<Scalar>::quiet_NaN();  // NaN: its length at the initial coordinates
  Scalar limit_lower = -std::numeric_limits<Scalar>::infinity(), limit_upper = std::numeric_limits<Scalar>::infinity();
  std::string name;
  // its limits' softness, as a dof's (JointDofConfig::limit_solref, limit_solimp)
  std::array<Scalar, 2> limit_solref = {0, 0};
  std::array<Scalar, 5> limit_solimp = {0.9, 0.95, 0.001, 0.5, 2};
  // dry friction along it: its force at most this either way, a row of the step soft as a dof's (friction_solref)
  Scalar frictionloss = 0;
  std::array<Scalar, 2> friction_solref = {0, 0};
  std::array<Scalar, 5> friction_solimp = {0.9, 0.95, 0.001, 0.5, 2};
};

// a body's ellipsoid in MuJoCo's ellipsoid fluid model (add_fluid_ellipsoid, a geom's fluidshape): its drag and lift
// coefficients (MuJoCo's fluidcoef, its defaults) and the fluid's virtual mass and moments of inertia per unit
// density (m^3, m^5) along its axes, NaN: the ellipsoid's own (Tuckerman's coefficients from its semi-axes)
struct FluidEllipsoidOptions {
  Scalar blunt_drag = 0.5, slender_drag = 0.25, angular_drag = 1.5, kutta_lift = 1, magnus_lift = 1;
  Vec3 added_mass = Vec3::Constant(std::numeric_limits<Scalar>::quiet_NaN());
  Vec3 added_inertia = Vec3::Constant(std::numeric_limits<Scalar>::quiet_NaN());
};

// an element of a spatial tendon's path (add_spatial_tendon; model.h's TendonPathKind): its kind, its body (-1: the
// world), its frame in the body's frame (a site's point; a sphere's centre, a cylinder's pose, its axis the frame's
// z) and its size (a sphere's or cylinder's radius, a pulley's divisor; a site's unused)
struct TendonPathElement {
  TendonPathKind kind = TendonPathKind::Site;
  int body = -1;
  Transform frame;
  Scalar size = 0;
};

// a sensor's options (add_sensor): its frame on its body, Touch's zone, a cutoff and a name
struct SensorOptions {
  Transform xform;  // the sensor's frame in its body's frame (in the world for the world, body -1)
  // Touch's zone in the frame: -1 the whole body, or Sphere (radius), Box (half extents), Ellipsoid (semi-axes),
  // Capsule or Cylinder (radius, half length, along the frame's z axis as MuJoCo's sites)
  int zone_type = -1;
  Vec3 zone_size = Vec3::Zero();
  Scalar cutoff = 0;  // values clamped to [-cutoff, cutoff] (Touch: to cutoff); 0: none; never quaternions or axes
  int shape = -1;     // Touch, ContactForce: only the contacts of this shape of the body (-1: all the body's)
  std::string name;
};

struct ImportOptions {
  Transform xform;            // places the file's world frame in the builder's world
  bool static_shapes = true;  // geoms of the world body and bodies welded to it (a floor)
};

struct JointOptions {
  Transform parent_xform;  // parent link frame -> parent joint frame
  Transform child_xform;   // child link frame -> child joint frame
  JointDofConfig dof;
  std::string name;
};

class ModelBuilder {
 public:
  // A builder's gravity, precision and timestep are given (the constructor's gravity, the setters) or not (the
  // defaults: gravity (0, -9.81, 0), Float64, 0.002 s). One not given takes the first given one of what is added
  // to it (add_builder, replicate, build_worlds; add_mjcf gives the file's gravity and timestep); a given gravity
  // or precision that differs from another given one fails naming both (timesteps: the first given stays)
  ModelBuilder() = default;
  explicit ModelBuilder(const Vec3& gravity);

  void set_gravity(const Vec3& gravity);
  const Vec3& gravity() const { return gravity_; }
  bool gravity_given() const { return gravity_given_; }
  // the precision the solver's batched kernels step the finalized model in (default Float64)
  void set_precision(Precision precision);
  Precision precision() const { return precision_; }
  // the step the scene was made for (model.timestep; MJCF's <option timestep>), in s
  void set_timestep(Scalar timestep);
  Scalar timestep() const { return timestep_; }

  // xform: the body's initial pose in the world; used for free bodies and Free joints
  int add_body(const RigidBody& body, const Transform& xform = Transform::identity(), const std::string& name = "");
  // the share of the body's weight a force through its centre of mass carries (MuJoCo's body gravcomp: 0 none, the
  // default; 1 the body floats; any finite value)
  void set_body_gravcomp(int body, Scalar gravcomp);

  int add_joint_revolute(int parent, int child, const JointOptions& options = {});
  int add_joint_prismatic(int parent, int child, const JointOptions& options = {});
  int add_joint_slide(int parent, int child, const JointOptions& options = {}) {
    return add_joint_prismatic(parent, child, options);
  }
  int add_joint_ball(int parent, int child, const JointOptions& options = {});
  int add_joint_fixed(int parent, int child, const JointOptions& options = {});
  // a Free joint must be a root (parent -1): its q is the child's pose in the world
  int add_joint_free(int parent, int child, const JointOptions& options = {});
  // Revolute, Prismatic, Ball, Fixed or Free (the maximal-coordinate joints have their own adders)
  int add_joint(JointType type, int parent, int child, const JointOptions& options);

  // The maximal-coordinate joints (builder_maximal_joints.cpp; kernels/joint.h: each is kinematically a Free joint
  // relative to its parent, starting at the child's placement relative to its parent's placement: add_body's xform).
  // SolverSemiImplicit and SolverXPBD enforce them, SolverFeatherstone refuses them. A compliance (m/N, rad/(N m); 0:
  // rigid) makes a constraint a spring of stiffness 1 / compliance (model.joint_compliance: linear, angular). Distance:
  // the parent and child joint frames' origins (the anchors) stay between min_distance and max_distance apart
  // (model.joint_limit_lower / upper of its first dof)
  int add_joint_distance(int parent, int child, const JointOptions& options, Scalar min_distance, Scalar max_distance,
                         Scalar compliance = 0);
  // D6: per axis of the joint frame locked, free, limited or driven. linear_axes and angular_axes (each at most 3,
  // options.dof is not read) give the axes that are not locked, in the parent joint frame, with their limits, drive
  // gains and damping; the joint frame is rotated so its x, y and z are the distinct given axes in order (linear
  // first, then angular; a direction given for both is one axis), completed to a right-handed frame. The D6's dofs
  // are that frame's: angular x, y, z, then linear x, y, z (a Free joint's [w; v]); a locked axis has the range
  // [0, 0]. Its angular coordinates are the rotation vector of the child joint frame in the parent's
  int add_joint_d6(int parent, int child, const JointOptions& options, const std::vector<JointDofConfig>& linear_axes,
                   const std::vector<JointDofConfig>& angular_axes, Scalar linear_compliance = 0,
                   Scalar angular_compliance = 0);
  // Cable: a segment of a rope or cable held to its parent segment at the joint frames, stretching with
  // stretch_compliance and bending and twisting with bend_compliance (an all-locked D6 of those compliances)
  int add_joint_cable(int parent, int child, const JointOptions& options, Scalar stretch_compliance = 0,
                      Scalar bend_compliance = 0);

  // joints: contiguous, ascending, each parent inside the articulation or the world
  int add_articulation(const std::vector<int>& joints);

  // plane through `offset * normal` with the given normal, static (body -1); options.xform is ignored
  int add_plane(const Vec3& normal, Scalar offset, const ShapeOptions& options = {});
  int add_ground_plane(Scalar y = 0, const ShapeOptions& options = {});
  int add_shape_box(int body, const Vec3& half_extents, const ShapeOptions& options = {});
  int add_shape_sphere(int body, Scalar radius, const ShapeOptions& options = {});
  // capsule and cylinder along the shape frame's local Y axis
  int add_shape_capsule(int body, Scalar radius, Scalar half_height, const ShapeOptions& options = {});
  int add_shape_cylinder(int body, Scalar radius, Scalar half_height, const ShapeOptions& options = {});
  // ellipsoid of semi-axes radii along the shape frame's X, Y and Z
  int add_shape_ellipsoid(int body, const Vec3& radii, const ShapeOptions& options = {});
  // a mesh (its vertices, in the frame of the shapes that will use it) for add_shape_mesh; it collides as its
  // convex hull (fails naming it where the points span no volume, are fewer than 4 or not finite)
  int add_mesh(const std::vector<Vec3>& vertices, const std::string& name = "");
  int add_shape_mesh(int body, int mesh, const ShapeOptions& options = {});

  // an actuator on a Revolute or Prismatic joint, MuJoCo's affine one (engine/model/actuator.h):
  // force = clamp(gain clamp(ctrl, ctrl range) + bias[0] + bias[1] gear q + bias[2] gear qd, force range),
  // tau = gear force; its position and velocity terms are integrated implicitly
  int add_actuator(int joint, const ActuatorOptions& options = {});
  // a position servo: gain kp, bias [0, -kp, -kv]
  int add_position(int joint, Scalar kp, Scalar kv = 0, const ActuatorOptions& options = {});
  // a velocity servo: gain kv, bias [0, 0, -kv]
  int add_velocity(int joint, Scalar kv, const ActuatorOptions& options = {});
  // a motor: gain 1, no bias, tau = gear * clamp(clamp(ctrl, ctrl range), force range)
  int add_motor(int joint, Scalar gear = 1, Scalar ctrl_lower = -std::numeric_limits<Scalar>::infinity(),
                Scalar ctrl_upper = std::numeric_limits<Scalar>::infinity(),
                Scalar force_lower = -std::numeric_limits<Scalar>::infinity(),
                Scalar force_upper = std::numeric_limits<Scalar>::infinity(), const std::string& name = "");

  // a fixed tendon (model.h): length = sum coefs[i] q(joints[i]) over Revolute or Prismatic joints, with a
  // spring, a damper (both taken explicitly) and limits (rows of the step, as a joint's). Its joints' articulations
  // become one at finalize where they are of fixed base and one after another (a gripper's fingers hanging from a
  // static palm); articulations given by add_articulation and floating ones are not joined (an error)
  int add_tendon(const std::vector<int>& joints, const std::vector<Scalar>& coefs, const TendonOptions& options = {});
  // a spatial tendon (MuJoCo's <spatial>, model.h): its length is its path's, from site to site, around each sphere or
  // cylinder between two sites where the straight piece would pass through it (on its side site's side where one
  // follows it), each piece after a pulley divided by its divisor; with the options' spring, damper, limits and dry
  // friction as a fixed tendon's, its forces pulling the sites and wraps. The path starts and ends at a site, a wrap
  // and a pulley stand between two sites; its bodies are in at most two articulations, one of them moving
  int add_spatial_tendon(const std::vector<TendonPathElement>& path, const TendonOptions& options = {});
  // an actuator on tendon `tendon`: add_actuator's force with the tendon's length and velocity in place of a
  // joint's, pulling along the tendon; taken explicitly
  int add_tendon_actuator(int tendon, const ActuatorOptions& options = {});
  // an actuator on a site (MuJoCo's site transmission, as quadrotors' thrusters): add_actuator's force f with no
  // position or velocity (bias[2] must be 0; options.gear must be 1, the gear is `gear`) pushes `body` at the site
  // `site` (its frame in the body's) with the force f gear[0..3) and the torque f gear[3..6), both in the site frame
  int add_site_actuator(int body, const Transform& site, const std::array<Scalar, 6>& gear,
                        const ActuatorOptions& options = {});

  // an equality constraint (model.h), held by rows of the step: the point `anchor` of body1 (its frame) stays
  // on the point of body2 (-1: the world) that coincides with it at the initial coordinates, or on `anchor2`
  // (body2's frame) where that is finite (MuJoCo's connect)
  int add_connect(int body1, int body2, const Vec3& anchor, const std::string& name = "",
                  const Vec3& anchor2 = Vec3::Constant(std::numeric_limits<Scalar>::quiet_NaN()));
  // body2 (-1: the world) held to body1 in the pose `relative` (body2's frame in body1's), as at the initial
  // coordinates if not given; the position rows keep body2's point `anchor` (its frame) in place (MuJoCo's weld)
  int add_weld(int body1, int body2, const std::string& name = "", const Vec3& anchor = Vec3::Zero(),
               const std::optional<Transform>& relative = std::nullopt);
  // joint1's coordinate follows the polynomial poly (a0 .. a4) of joint2's, both from their initial
  // coordinates (joint2 -1: joint1 stays at a0 from its own); Revolute or Prismatic joints (MuJoCo's joint
  // equality)
  int add_joint_coupling(int joint1, int joint2, const std::array<Scalar, 5>& poly, const std::string& name = "");
  // equality e's rows soft as MuJoCo's equality solref and solimp (JointDofConfig::limit_solref says how; an
  // equality's rows are hard until this is called)
  void set_equality_softness(int e, const std::array<Scalar, 2>& solref, const std::array<Scalar, 5>& solimp);

  // a sensor (model.h's SensorType) of `object`: a joint (JointPos, JointVel: Revolute or Prismatic; BallQuat,
  // BallAngVel: Ball), a tendon (TendonPos, TendonVel) or a body, -1 the world (every other type); its values are
  // State::sensor_data[sensor_start[s] ..), computed by a solver's step from the state it starts from, with the
  // step's accelerations and contact forces (MuJoCo's sensordata after mj_step)
  int add_sensor(SensorType type, int object, const SensorOptions& options = {});
  int sensor_count() const { return static_cast<int>(sensors_.size()); }

  // the rule shape_collision_group and shape_collision_mask filter pairs by (model.h); add_mjcf sets Mujoco
  void set_collision_filter(CollisionFilter filter) { collision_filter_ = filter; }
  // how contacts combine their shapes' friction (model.h); add_mjcf sets Mujoco
  void set_friction_rule(FrictionRule rule) { friction_rule_ = rule; }
  // MuJoCo's impratio for soft contacts (model.impratio)
  void set_impratio(Scalar impratio);
  // the medium the bodies move through, MuJoCo's <option density viscosity wind> (model.fluid_*: its inertia-box
  // model, engine/solver/parts/applied_wrenches.h): density (kg/m^3) and viscosity (Pa s) >= 0, the wind (m/s)
  void set_fluid(Scalar density, Scalar viscosity, const Vec3& wind = Vec3::Zero());
  // body `body` feels the fluid (set_fluid) as MuJoCo's ellipsoid model of an ellipsoid at `frame` (in the body's
  // frame) with semi-axes `semi_axes` along the frame's axes, in place of the box of its inertia: added mass,
  // viscous and quadratic drag, Kutta and Magnus lift (model.h; one body may have several)
  int add_fluid_ellipsoid(int body, const Transform& frame, const Vec3& semi_axes,
                          const FluidEllipsoidOptions& options = {});
  FrictionRule friction_rule() const { return friction_rule_; }
  CollisionFilter collision_filter() const { return collision_filter_; }
  // shapes a and b never collide (MuJoCo's <exclude>, by shape)
  void exclude_shapes(int a, int b);
  // no shape of body a collides with a shape of body b (those added so far; -1: the static shapes)
  void exclude_bodies(int body_a, int body_b);
  // a keyframe over the joints and actuators added so far: their coordinates joint_q, velocities joint_qd and
  // commands ctrl (empty: zero), in the order the joints and actuators were added; keyframes of one name
  // from several builders (replicated worlds) make one keyframe of the model, coordinates no keyframe names
  // keeping the initial ones
  void add_keyframe(const std::string& name, const std::vector<Scalar>& joint_q,
                    const std::vector<Scalar>& joint_qd = {}, const std::vector<Scalar>& ctrl = {});
  // appends everything of `other` (bodies, joints, articulations, shapes, actuators, keyframes) as world `world`
  // (-1: a new world), its root joints, free bodies and static shapes placed by xform
  void add_builder(const ModelBuilder& other, const Transform& xform = {}, int world = -1);
  // world_count copies of `other`, copy i shifted by i * spacing, one world each
  void replicate(const ModelBuilder& other, int world_count, const Vec3& spacing = Vec3::Zero());
  int world_count() const { return world_count_; }

  // MJCF / URDF import through MuJoCo's parser (engine/import/mjcf_import.cpp): returns the warnings
  // for everything in the file the engine does not model, by name
  std::vector<std::string> add_mjcf(const std::string& path, const ImportOptions& options = {});
  std::vector<std::string> add_urdf(const std::string& path, const ImportOptions& options = {}) {
    return add_mjcf(path, options);
  }

  int body_count() const { return static_cast<int>(body_mass_.size()); }
  int joint_count() const { return static_cast<int>(joints_.size()); }
  int shape_count() const { return static_cast<int>(shapes_.size()); }
  int actuator_count() const { return static_cast<int>(actuators_.size()); }
  int tendon_count() const { return static_cast<int>(tendons_.size()); }
  int equality_count() const { return static_cast<int>(equalities_.size()); }

  // bodies no joint names as their child get an implicit Free joint in an articulation of their own
  Model finalize() const;

 private:
  friend class MjcfImporter;
  struct JointRecord {
    JointRecord(JointType type_, int parent_, int child_, const JointOptions& options_)
        : type(type_), parent(parent_), child(child_), options(options_) {}
    JointType type;
    int parent, child;
    JointOptions options;
    int articulation = -1;
    std::vector<JointDofConfig> dofs;  // per dof where they differ (a D6's, a Distance's); empty: options.dof
    Scalar compliance[2] = {0, 0};     // linear, angular (model.joint_compliance)
  };
  struct ShapeRecord {
    ShapeType type;
    int body;
    Vec3 scale;
    ShapeOptions options;
    int mesh = -1;
  };
  // a mesh's hull centred on origin (the point of its vertices' frame its shapes' frames move to); reach: the
  // hull's largest |coordinate| along each axis (a Mesh shape's scale, for its bounds)
  struct MeshRecord {
    std::shared_ptr<const ConvexHull> hull;
    Vec3 origin, reach;
  };

  // massless links are allowed for imported bodies that carry several MuJoCo joints
  int add_body_checked(const RigidBody& body, const Transform& xform, const std::string& name, bool allow_massless);
  // the joint checked (bodies, frames, limits and gains of options.dof and of each of joint.dofs; its adder checks
  // its compliance) and added
  int add_joint_record(JointRecord joint);
  int add_shape(ShapeType type, int body, const Vec3& scale, const ShapeOptions& options, int mesh = -1);
  // the implicit Free joint of a body no joint names as its child
  JointRecord free_joint(int body) const;

  // finalize() in stages, in this order:
  // the joints with their articulations assigned, an implicit Free joint appended per unjointed body
  std::vector<JointRecord> articulated_joints(int& articulation_count) const;
  // joins the implicit articulations of fixed base that a fixed tendon couples into one (a forest: a gripper's
  // fingers hanging from a static palm); errors name the tendon where it couples others
  void join_tendon_articulations(std::vector<JointRecord>& joints, int& articulation_count) const;
  // the Model's joint table, coordinate and dof starts and articulation starts
  void lay_out_joints(const std::vector<JointRecord>& joints, Model& model) const;
  // one joint's per-dof parameters and its q0 / q_ref coordinates (coordinates from q, dofs from qd)
  void lay_out_joint_dofs(const JointRecord& joint, int q, int qd, Model& model) const;
  // the Model's body mass properties, names and worlds
  void lay_out_bodies(Model& model) const;
  // the Model's shape table, and the hulls of its meshes
  void lay_out_shapes(Model& model) const;
  void lay_out_meshes(Model& model) const;
  // the Model's actuator table
  void lay_out_actuators(Model& model) const;
  // the world of tendon t (its first joint's, its path's first moving body's)
  int tendon_world(int t) const;
  // a tendon's options checked (add_tendon, add_spatial_tendon), errors naming `item`
  void check_tendon_options(const std::string& item, const TendonOptions& options) const;
  // the Model's tendon and equality tables (builder_constraints.cpp; equalities after the other tables)
  void lay_out_tendons(Model& model) const;
  // the Model's fluid ellipsoids (builder_shapes.cpp)
  void lay_out_fluid_ellipsoids(Model& model) const;
  void lay_out_equalities(Model& model) const;
  // the Model's keyframes, by name in the order first added
  void lay_out_keyframes(Model& model) const;
  // the Model's sensor table (builder_sensors.cpp)
  void lay_out_sensors(Model& model) const;
  // add_actuator, its errors naming the kind of actuator ("a motor")
  int add_actuator_of(const char* kind, int joint, const ActuatorOptions& options);
  // fails (item: ...) unless `joint` is the index of a Revolute or Prismatic joint; `needs` says what needs one
  // ("a motor drives a Revolute or Prismatic joint")
  void check_scalar_joint(const std::string& item, const std::string& needs, int joint) const;

  // a given gravity from `source` ("the file's"): set where this builder has none given, else it must be the same
  void take_gravity(const Vec3& gravity, const char* source);
  // a given timestep: set where this builder has none given (a scene of robots from files of different timesteps
  // keeps the first)
  void take_timestep(Scalar timestep);
  // what `other` gives of gravity, precision and timestep, taken so (add_builder)
  void take_settings(const ModelBuilder& other);

  Vec3 gravity_ = Vec3(0, -9.81, 0);
  Precision precision_ = Precision::Float64;
  Scalar timestep_ = 0.002;
  bool gravity_given_ = false, precision_given_ = false, timestep_given_ = false;
  std::vector<Scalar> body_mass_, body_gravcomp_;
  std::vector<Vec3> body_com_;
  std::vector<Mat3> body_inertia_;
  std::vector<Transform> body_xform_;
  std::vector<std::string> body_name_;
  std::vector<int> body_joint_;  // joint whose child the body is, -1
  std::vector<int> body_world_;
  std::vector<int> shape_world_;  // -1: a static shape every world collides with
  int world_count_ = 0;
  std::vector<JointRecord> joints_;
  std::vector<ShapeRecord> shapes_;
  std::vector<MeshRecord> meshes_;
  struct ActuatorRecord {
    int joint;  // -1 on a tendon or a site
    ActuatorOptions options;
    int tendon = -1;
    int body = -1;                      // on a site of this body
    std::array<Scalar, 6> wrench = {};  // a site's: of a unit force, in the body frame (model.h)
  };
  struct TendonRecord {
    std::vector<int> joints;  // (a fixed tendon's)
    std::vector<Scalar> coefs;
    TendonOptions options;
    std::vector<TendonPathElement> path;  // (a spatial tendon's)
  };
  std::vector<TendonRecord> tendons_;
  struct EqualityRecord {
    EqualityType type;
    int object[2];  // bodies or joints
    Scalar data[10];
    std::string name;
    std::array<Scalar, 2> solref = {0, 0};
    std::array<Scalar, 5> solimp = {0.9, 0.95, 0.001, 0.5, 2};
  };
  std::vector<EqualityRecord> equalities_;
  struct SensorRecord {
    SensorType type;
    int object;  // joint, tendon or body (-1: the world)
    SensorOptions options;
    int world;  // its object's (a sensor of the world, object -1: the builder's world it was added to)
  };
  std::vector<SensorRecord> sensors_;
  std::vector<ActuatorRecord> actuators_;
  // a keyframe's values for joints [joint_begin, joint_end) and actuators from actuator_begin
  struct KeyframeRecord {
    std::string name;
    int joint_begin, joint_end, actuator_begin;
    std::vector<Scalar> q, qd, ctrl;
  };
  std::vector<KeyframeRecord> keyframes_;
  std::vector<std::pair<int, int>> excluded_;  // shape pairs
  CollisionFilter collision_filter_ = CollisionFilter::GroupAndMask;
  FrictionRule friction_rule_ = FrictionRule::GeometricMean;
  Scalar impratio_ = 1;
  Scalar fluid_density_ = 0, fluid_viscosity_ = 0;
  Vec3 wind_ = Vec3::Zero();
  struct FluidEllipsoidRecord {
    int body;
    Transform frame;
    Vec3 semi_axes;
    FluidEllipsoidOptions options;  // (added mass and inertia filled in)
  };
  std::vector<FluidEllipsoidRecord> fluid_ellipsoids_;
  int articulation_count_ = 0;
};

}  // namespace novaphy
