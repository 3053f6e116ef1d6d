// Model (read-only after finalize), State and Control: flat structure-of-arrays buffers.
// One field table per entity (the X-macros below) drives allocation, size checks and the
// numpy views of the binding: adding a field is one line.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "kernels/articulation.h"

namespace novaphy {

// capsules and cylinders run along their frame's Y axis; a Mesh collides as the convex hull of mesh shape_mesh
enum class ShapeType : int { Plane = 0, Sphere = 1, Box = 2, Capsule = 3, Cylinder = 4, Ellipsoid = 5, Mesh = 6 };

enum class EqualityType : int { Connect = 0, JointCoupling = 1, Weld = 2 };

// an element of a spatial tendon's path (model.h, engine/model/spatial_tendon.h): a Site (a point riding on a body),
// a Sphere or Cylinder it wraps around (radius; a cylinder's axis its frame's z), the SideSite of the wrap before it
// (the side it passes on), a Pulley (its size the divisor of the path after it)
enum class TendonPathKind : int { Site = 0, Sphere = 1, Cylinder = 2, SideSite = 3, Pulley = 4 };

// the precision the batched kernels step a model in; with Float32 the stepped state is rounded to float each
// step, and its State and Control also hold their arrays as float32 (State::float32, Control::float32)
enum class Precision : int { Float64 = 0, Float32 = 1 };

// what a sensor measures (MuJoCo's sensor of the same name where MJCF has one; `frame` is the sensor's frame on its
// body, MuJoCo's site or the frame of the object it names; velocities and accelerations are the frame origin's):
// JointPos, JointVel (1): a Revolute or Prismatic joint's coordinate and velocity; BallQuat (4, [w x y z]),
// BallAngVel (3): a Ball joint's; FramePos (3), FrameQuat (4, [w x y z]), FrameXAxis/YAxis/ZAxis (3), FrameLinVel,
// FrameAngVel, FrameLinAcc, FrameAngAcc (3): the frame's in the world; Gyro, Velocimeter, Accelerometer (3): the
// frame's angular velocity, linear velocity and linear acceleration (gravity's reaction included: 9.81 up at
// rest) in the frame; Force, Torque (3): what the body's parent exerts on the body's subtree, at the frame's
// origin, in the frame; SubtreeCom (3): the centre of mass of the body's subtree in the world; Touch (1): the
// normal forces of the body's contacts whose ray (from the contact point, away from the body) meets the zone
// (sensor_zone; a zone of type -1 is the whole body); ContactForce (3): the force the body's contacts exert on it,
// in the world (both of the body's contacts, or of one of its shapes: sensor_shape, -1 for all); ProjectedGravity (3):
// the world's gravity direction in the frame; TendonPos, TendonVel (1): a tendon's length and velocity
enum class SensorType : int {
  JointPos = 0,
  JointVel,
  BallQuat,
  BallAngVel,
  FramePos,
  FrameQuat,
  FrameXAxis,
  FrameYAxis,
  FrameZAxis,
  FrameLinVel,
  FrameAngVel,
  FrameLinAcc,
  FrameAngAcc,
  Gyro,
  Velocimeter,
  Accelerometer,
  Force,
  Torque,
  SubtreeCom,
  Touch,
  ContactForce,
  ProjectedGravity,
  TendonPos,
  TendonVel,
};
constexpr int kSensorTypeCount = static_cast<int>(SensorType::TendonVel) + 1;
// the type's name as MJCF writes it ("gyro"; NovaPhy's own: "contactforce", "projectedgravity"), and as the enum
const char* sensor_type_name(SensorType type);
const char* sensor_type_label(SensorType type);
// the values a sensor of this type gives (1, 3 or 4)
int sensor_dim(SensorType type);
// what a sensor's sensor_object names: a joint, a body (-1: the world) or a tendon
enum class SensorObject : int { Joint = 0, Body = 1, Tendon = 2 };
SensorObject sensor_object_kind(SensorType type);
const char* precision_name(Precision precision);

// which shape pairs may collide, from each shape's shape_collision_group and shape_collision_mask:
// GroupAndMask (the builder's default): (group_a & mask_b) != 0 and (group_b & mask_a) != 0;
// Mujoco (a model that imported MJCF), MuJoCo's contype/conaffinity: (group_a & mask_b) != 0 or
// (group_b & mask_a) != 0. Either way a shape that can collide with no shape is visual only
enum class CollisionFilter : int { GroupAndMask = 0, Mujoco = 1 };

// a contact's friction coefficients (sliding shape_mu; with condim 4 torsional shape_mu_torsion, with 6 also
// rolling shape_mu_rolling, both lengths) from its shapes': GeometricMean (the builder's default) sqrt(mu_a mu_b);
// Mujoco (a model that imported MJCF), MuJoCo's rule: the shape of higher shape_priority decides, else the
// larger mu; a contact whose condim (the deciding shape's, else the larger) is 1 is frictionless
enum class FrictionRule : int { GeometricMean = 0, Mujoco = 1 };
const char* friction_rule_name(FrictionRule rule);
const char* collision_filter_name(CollisionFilter filter);
const char* shape_type_name(ShapeType type);

// X(type, name, count, width): `count` is an expression over the Model's counts.
// A fixed tendon t is a linear combination of Revolute and Prismatic coordinates of one articulation:
// length = sum of tendon_coef[e] joint_q[tendon_coord[e]] over its entries e in [tendon_start[t],
// tendon_start[t + 1]); a force f along it is tendon_coef[e] f on dof tendon_dof[e]. A spatial tendon has no joint
// entries but a path [tendon_path_start[t], tendon_path_start[t + 1]) (a fixed one none): each element's kind
// (TendonPathKind), body (-1: the world), frame in the body's frame ([p, q]: a site's point, a wrapped geom's pose)
// and size (a radius, a pulley's divisor); its length is its path's (engine/model/spatial_tendon.h). An actuator drives
// joint actuator_joint, or tendon actuator_tendon where actuator_joint is -1, or (both -1) pushes body
// actuator_body at a site, MuJoCo's site transmission: its force f is the wrench f actuator_wrench, in the body's
// frame (force, then torque about the body's origin: the gear's force and torque in the site frame, at the site).
// An equality constraint e (MuJoCo's, held by rows of the step) of equality_type Connect keeps the point
// equality_data[0..3) of body equality_object[0] (its frame) on the point equality_data[3..6) of body
// equality_object[1] (-1: the world frame); one of type JointCoupling keeps q1 - q1_0 = a0 + a1 x + a2 x^2 +
// a3 x^3 + a4 x^4, x = q2 - q2_0, for joints q1, q2 (Revolute or Prismatic) of equality_object (joint 2 -1:
// x = 0), a = equality_data[0..5), q1_0 and q2_0 equality_data[5], [6]; one of type Weld keeps, as a connect,
// equality_data[0..3) on [3..6) and body 2's orientation in body 1's frame at the quaternion equality_data[6..10)
// ([x, y, z, w]; body 1 -1: the world)
// A contact is soft, as MuJoCo's (engine/solver/parts/contact_softness.h), where its shapes' solref has a nonzero time
// constant: shape_solref (time constant, damping ratio; or -stiffness, -damping), shape_solimp (dmin, dmax, width,
// midpoint, power), shape_solmix (the weight of a shape's solref and solimp in a pair of equal priority),
// shape_margin (a contact is active from this distance) and shape_gap (less this). body_invweight0 is
// MuJoCo's: the mean of the diagonal of J M^-1 J^T at joint_q0 for the body's COM, translation then rotation.
// The rows of a dof's limits (joint_limit_solref, _solimp), its dry friction (joint_friction_), a tendon's limits
// (tendon_limit_) and dry friction (tendon_frictionloss, tendon_friction_) and an equality constraint (equality_) are
// soft as MuJoCo's (engine/solver/parts/soft_row.h) where their solref is not (0, 0), hard rows where it is;
// joint_invweight0 (M^-1's diagonal at joint_q0, averaged over a Ball's dofs and over a Free joint's translations and
// its rotations) and tendon_invweight0 (J M^-1 J^T) weigh them, MuJoCo's dof_invweight0 and tendon_invweight0, computed
// when some soft row needs them (else 0). A mesh m is a convex hull (kernels/hull.h): its vertices
// mesh_vertex[mesh_vertex_start[m] .. mesh_vertex_start[m + 1]) in the frame of the shapes that use it (centred on the
// vertices' mean), its faces [mesh_face_start[m] .. mesh_face_start[m + 1]), each with its plane (outward unit normal,
// offset) and its corners mesh_corner[mesh_corner_start[f] .. mesh_corner_start[f + 1]) (vertex indices within the
// mesh, counterclockwise seen from outside). A shape's shape_mesh is its mesh, -1 for other types. world_gravity: each
// world's gravity (the builder's gravity in every world at finalize). body_gravcomp: the share of a body's weight
// carried by a force through its centre of mass, MuJoCo's gravcomp (engine/solver/parts/gravity_compensation.h; 0:
// none, 1: it floats). A fluid ellipsoid e (MuJoCo's ellipsoid fluid model, a geom's fluidshape) rides on body
// fluid_ellipsoid_body[e] (ascending: a body's together) at fluid_ellipsoid_frame[e] ([p, q] in the body's frame) with
// semi-axes fluid_ellipsoid_size along the frame's axes, its drag coefficients (blunt, slender, angular), lift
// coefficients (Kutta, Magnus) and the fluid's virtual mass and moments of inertia per unit density (m^3, m^5) along
// the axes; a body with one feels the fluid through its ellipsoids, not through the box of its inertia
// (engine/solver/parts/applied_wrenches.h). joint_compliance: a maximal-coordinate joint's linear and angular
// compliance (builder.h: add_joint_distance, d6, cable; 0 rigid), read by the solvers in maximal coordinates. The
// parameters learning randomises may change per world after finalize, through Model::set_parameter only
// (engine/model/parameters.cpp lists them); every other field is the model's structure and stays as finalized.
#define NOVAPHY_MODEL_FIELDS(X)                                      \
  X(Scalar, body_mass, body_count, 1)                                \
  X(Scalar, body_com, body_count, 3)                                 \
  X(Scalar, body_inertia, body_count, 9)                             \
  X(int, body_world, body_count, 1)                                  \
  X(Scalar, body_invweight0, body_count, 2)                          \
  X(Scalar, body_gravcomp, body_count, 1)                            \
  X(int, joint_type, joint_count, 1)                                 \
  X(int, joint_parent, joint_count, 1)                               \
  X(int, joint_child, joint_count, 1)                                \
  X(int, joint_ancestor, joint_count, 1)                             \
  X(int, joint_articulation, joint_count, 1)                         \
  X(int, joint_q_start, joint_count + 1, 1)                          \
  X(int, joint_qd_start, joint_count + 1, 1)                         \
  X(Scalar, joint_X_p, joint_count, 7)                               \
  X(Scalar, joint_X_c, joint_count, 7)                               \
  X(Scalar, joint_axis, joint_count, 3)                              \
  X(Scalar, joint_compliance, joint_count, 2)                        \
  X(Scalar, joint_q0, joint_coord_count, 1)                          \
  X(Scalar, joint_q_ref, joint_coord_count, 1)                       \
  X(Scalar, joint_armature, joint_dof_count, 1)                      \
  X(Scalar, joint_damping, joint_dof_count, 1)                       \
  X(Scalar, joint_frictionloss, joint_dof_count, 1)                  \
  X(Scalar, joint_stiffness, joint_dof_count, 1)                     \
  X(Scalar, joint_limit_lower, joint_dof_count, 1)                   \
  X(Scalar, joint_limit_upper, joint_dof_count, 1)                   \
  X(Scalar, joint_target_ke, joint_dof_count, 1)                     \
  X(Scalar, joint_target_kd, joint_dof_count, 1)                     \
  X(Scalar, joint_limit_solref, joint_dof_count, 2)                  \
  X(Scalar, joint_limit_solimp, joint_dof_count, 5)                  \
  X(Scalar, joint_friction_solref, joint_dof_count, 2)               \
  X(Scalar, joint_friction_solimp, joint_dof_count, 5)               \
  X(Scalar, joint_invweight0, joint_dof_count, 1)                    \
  X(int, articulation_start, articulation_count + 1, 1)              \
  X(int, shape_type, shape_count, 1)                                 \
  X(int, shape_body, shape_count, 1)                                 \
  X(Scalar, shape_transform, shape_count, 7)                         \
  X(Scalar, shape_scale, shape_count, 3)                             \
  X(Scalar, shape_mu, shape_count, 1)                                \
  X(Scalar, shape_mu_torsion, shape_count, 1)                        \
  X(Scalar, shape_mu_rolling, shape_count, 1)                        \
  X(Scalar, shape_restitution, shape_count, 1)                       \
  X(int, shape_collision_group, shape_count, 1)                      \
  X(int, shape_collision_mask, shape_count, 1)                       \
  X(int, shape_priority, shape_count, 1)                             \
  X(int, shape_condim, shape_count, 1)                               \
  X(Scalar, shape_solref, shape_count, 2)                            \
  X(Scalar, shape_solimp, shape_count, 5)                            \
  X(Scalar, shape_solmix, shape_count, 1)                            \
  X(Scalar, shape_margin, shape_count, 1)                            \
  X(Scalar, shape_gap, shape_count, 1)                               \
  X(int, shape_world, shape_count, 1)                                \
  X(int, shape_mesh, shape_count, 1)                                 \
  X(int, mesh_vertex_start, mesh_count + 1, 1)                       \
  X(Scalar, mesh_vertex, mesh_vertex_count, 3)                       \
  X(int, mesh_face_start, mesh_count + 1, 1)                         \
  X(Scalar, mesh_face_plane, mesh_face_count, 4)                     \
  X(int, mesh_corner_start, mesh_face_count + 1, 1)                  \
  X(int, mesh_corner, mesh_corner_count, 1)                          \
  X(int, exclude_shape, exclude_count, 2)                            \
  X(int, tendon_start, tendon_count + 1, 1)                          \
  X(int, tendon_coord, tendon_entry_count, 1)                        \
  X(int, tendon_dof, tendon_entry_count, 1)                          \
  X(Scalar, tendon_coef, tendon_entry_count, 1)                      \
  X(Scalar, tendon_stiffness, tendon_count, 1)                       \
  X(Scalar, tendon_damping, tendon_count, 1)                         \
  X(Scalar, tendon_rest_length, tendon_count, 1)                     \
  X(Scalar, tendon_limit_lower, tendon_count, 1)                     \
  X(Scalar, tendon_limit_upper, tendon_count, 1)                     \
  X(Scalar, tendon_limit_solref, tendon_count, 2)                    \
  X(Scalar, tendon_limit_solimp, tendon_count, 5)                    \
  X(Scalar, tendon_frictionloss, tendon_count, 1)                    \
  X(Scalar, tendon_friction_solref, tendon_count, 2)                 \
  X(Scalar, tendon_friction_solimp, tendon_count, 5)                 \
  X(Scalar, tendon_invweight0, tendon_count, 1)                      \
  X(int, tendon_path_start, tendon_count + 1, 1)                     \
  X(int, tendon_path_kind, tendon_path_count, 1)                     \
  X(int, tendon_path_body, tendon_path_count, 1)                     \
  X(Scalar, tendon_path_frame, tendon_path_count, 7)                 \
  X(Scalar, tendon_path_size, tendon_path_count, 1)                  \
  X(int, equality_type, equality_count, 1)                           \
  X(int, equality_object, equality_count, 2)                         \
  X(Scalar, equality_data, equality_count, 10)                       \
  X(Scalar, equality_solref, equality_count, 2)                      \
  X(Scalar, equality_solimp, equality_count, 5)                      \
  X(int, actuator_joint, actuator_count, 1)                          \
  X(int, actuator_tendon, actuator_count, 1)                         \
  X(int, actuator_body, actuator_count, 1)                           \
  X(Scalar, actuator_wrench, actuator_count, 6)                      \
  X(Scalar, actuator_gear, actuator_count, 1)                        \
  X(Scalar, actuator_gain, actuator_count, 1)                        \
  X(Scalar, actuator_bias, actuator_count, 3)                        \
  X(Scalar, actuator_ctrl_lower, actuator_count, 1)                  \
  X(Scalar, actuator_ctrl_upper, actuator_count, 1)                  \
  X(Scalar, actuator_force_lower, actuator_count, 1)                 \
  X(Scalar, actuator_force_upper, actuator_count, 1)                 \
  X(Scalar, world_gravity, world_count, 3)                           \
  X(int, fluid_ellipsoid_body, fluid_ellipsoid_count, 1)             \
  X(Scalar, fluid_ellipsoid_frame, fluid_ellipsoid_count, 7)         \
  X(Scalar, fluid_ellipsoid_size, fluid_ellipsoid_count, 3)          \
  X(Scalar, fluid_ellipsoid_drag, fluid_ellipsoid_count, 3)          \
  X(Scalar, fluid_ellipsoid_lift, fluid_ellipsoid_count, 2)          \
  X(Scalar, fluid_ellipsoid_added_mass, fluid_ellipsoid_count, 3)    \
  X(Scalar, fluid_ellipsoid_added_inertia, fluid_ellipsoid_count, 3) \
  X(Scalar, keyframe_q, keyframe_count, joint_coord_count)           \
  X(Scalar, keyframe_qd, keyframe_count, joint_dof_count)            \
  X(Scalar, keyframe_ctrl, keyframe_count, actuator_count)           \
  X(int, sensor_type, sensor_count, 1)                               \
  X(int, sensor_object, sensor_count, 1)                             \
  X(Scalar, sensor_frame, sensor_count, 7)                           \
  X(Scalar, sensor_zone, sensor_count, 4)                            \
  X(Scalar, sensor_cutoff, sensor_count, 1)                          \
  X(int, sensor_shape, sensor_count, 1)                              \
  X(int, sensor_world, sensor_count, 1)                              \
  X(int, sensor_start, sensor_count + 1, 1)

// world_reset: 1 where Model::reset_worlds or restart_worlds reset the world, or a step's divergence guard restarted
// it (on_divergence Reset): the next collide and step from this state use none of the world's past (its contacts'
// and rows' warm starts, a kept mass-matrix factor); a step writes 0 into its output's other worlds
#define NOVAPHY_STATE_FIELDS(X)                \
  X(Scalar, joint_q, joint_coord_count, 1)     \
  X(Scalar, joint_qd, joint_dof_count, 1)      \
  X(Scalar, body_q, body_count, 7)             \
  X(Scalar, body_qd, body_count, 6)            \
  X(Scalar, body_f, body_count, 6)             \
  X(std::uint8_t, world_reset, world_count, 1) \
  X(Scalar, sensor_data, sensor_value_count, 1)

// joint_f: generalised forces; actuator_ctrl: motor commands (force = gear * clamp(ctrl), clamped);
// PD drives per dof: tau = ke (target_pos - q) + kd (target_vel - qd), integrated implicitly by the
// solver (ke acts on Revolute and Prismatic joints; ke/kd start at the model's joint_target_ke/kd)
#define NOVAPHY_CONTROL_FIELDS(X)                 \
  X(Scalar, joint_f, joint_dof_count, 1)          \
  X(Scalar, actuator_ctrl, actuator_count, 1)     \
  X(Scalar, joint_target_pos, joint_dof_count, 1) \
  X(Scalar, joint_target_vel, joint_dof_count, 1) \
  X(Scalar, joint_target_ke, joint_dof_count, 1)  \
  X(Scalar, joint_target_kd, joint_dof_count, 1)

// the counts every field's size is written in, the precision of the model's State and Control arrays, and the
// model they were made by: model_id is a fingerprint of the
// model as finalized (every field, gravity and the enums), so a state, control or contacts of another model is
// refused even where its counts are the same, while models finalized alike (a scene rebuilt) share their states
struct ModelCounts {
  std::uint64_t model_id = 0;
  Precision precision = Precision::Float64;
  int world_count = 1;
  int body_count = 0;
  int joint_count = 0;
  int joint_coord_count = 0;
  int joint_dof_count = 0;
  int articulation_count = 0;
  int shape_count = 0;
  int actuator_count = 0;
  int keyframe_count = 0;
  int exclude_count = 0;
  int tendon_count = 0;
  int tendon_entry_count = 0;  // a tendon's joints, all tendons together
  int tendon_path_count = 0;   // the spatial tendons' path elements, all together
  int fluid_ellipsoid_count = 0;
  int equality_count = 0;
  int mesh_count = 0;
  int mesh_vertex_count = 0;  // all meshes' hull vertices together
  int mesh_face_count = 0;
  int mesh_corner_count = 0;  // all faces' corners together
  int sensor_count = 0;
  int sensor_value_count = 0;  // all sensors' values together
};

bool same_layout(const ModelCounts& a, const ModelCounts& b);

// a field's type among a float32 model's float32 arrays: Scalar as float, flags as they are
template <typename T>
using Float32Of = std::conditional_t<std::is_same_v<T, Scalar>, float, T>;

// a Float32 model's State and Control as float32 arrays (empty for a Float64 model): what the Python binding
// hands out (numpy views, DLPack without a copy to torch or JAX) and a float32 policy reads and writes in place.
// The engine reads and writes the double fields; from_float32() widens these arrays into them and to_float32()
// rounds them into these arrays, exact both ways for a float32 model's stepped state (rounded to float each step)
#define NOVAPHY_DECLARE_FLOAT32(T, name, count, width) std::vector<Float32Of<T>> name;
struct StateFloat32 {
  NOVAPHY_STATE_FIELDS(NOVAPHY_DECLARE_FLOAT32)
};
struct ControlFloat32 {
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_DECLARE_FLOAT32)
};
#undef NOVAPHY_DECLARE_FLOAT32

struct State : ModelCounts {
#define NOVAPHY_DECLARE(T, name, count, width) std::vector<T> name;
  NOVAPHY_STATE_FIELDS(NOVAPHY_DECLARE)
  StateFloat32 float32;  // (precision Float32)
  // copies every array of other (a checkpoint restored); throws Error unless both have one model's layout and
  // precision
  void assign(const State& other);
  // the fields from the float32 arrays / the float32 arrays from the fields, on `threads` threads (0: OpenMP's
  // default); nothing for a Float64 state
  void from_float32(int threads = 0);
  void to_float32(int threads = 0);
};

struct Control : ModelCounts {
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_DECLARE)
  ControlFloat32 float32;  // (precision Float32)
  void assign(const Control& other);
  void from_float32(int threads = 0);
  void to_float32(int threads = 0);
};

struct ParameterIndex;  // engine/model/parameters.cpp

struct Model : ModelCounts {
  Vec3 gravity = Vec3(0, -9.81, 0);  // the builder's: every world's world_gravity at finalize
  CollisionFilter collision_filter = CollisionFilter::GroupAndMask;  // exclude_shape: pairs that never collide
  FrictionRule friction_rule = FrictionRule::GeometricMean;
  NOVAPHY_MODEL_FIELDS(NOVAPHY_DECLARE)
#undef NOVAPHY_DECLARE
  Scalar timestep = 0.002;  // (s) the step the scene was made for (MJCF's <option timestep>)
  Scalar impratio = 1;      // MuJoCo's ratio of a soft contact's normal to frictional regularisation
  // the medium's density (kg/m^3) and viscosity (Pa s) and the wind (m/s, world): MuJoCo's inertia-box fluid forces
  // where either is > 0 (ModelBuilder::set_fluid)
  Scalar fluid_density = 0, fluid_viscosity = 0;
  Vec3 wind = Vec3::Zero();
  std::vector<std::string> body_name;
  std::vector<std::string> joint_name;
  std::vector<std::string> shape_name;
  std::vector<std::string> actuator_name;
  std::vector<std::string> tendon_name;
  std::vector<std::string> equality_name;
  std::vector<std::string> sensor_name;
  std::vector<std::string> keyframe_name;  // keyframe k's joint_q, joint_qd and actuator_ctrl: row k of keyframe_*

  // sizes every field from the counts (fields are zero-filled)
  void allocate();
  // model_id from every field as it is now (the builder's last step)
  void set_model_id();
  // throws Error naming the first field whose size does not match the counts
  void check_sizes() const;

  ArticulationView articulation(int a) const;
  // the world of tendon t (its first joint's; a spatial one's: its path's first moving body's)
  int tendon_world(int t) const;
  // the world of articulation a (its root body's; -1: none)
  int articulation_world(int a) const { return body_world[joint_child[articulation_start[a]]]; }
  // a state at the initial coordinates joint_q0 (or keyframe `keyframe`'s coordinates and velocities), with
  // body_q/body_qd from forward kinematics
  State state() const;
  State state(const std::string& keyframe) const;
  // worlds `worlds` of `state` (world ids, in any order, repeats allowed) back to the initial coordinates joint_q0
  // at rest, or to keyframe `keyframe`'s coordinates and velocities: their joint_q, joint_qd, body_f (zero),
  // body_q and body_qd (forward kinematics, the worlds' articulations on `threads` threads, 0: OpenMP's default),
  // sensor_data (zero) and world_reset (1); every other entry of the state is left as it was. Throws Error naming a
  // world id out of range, a keyframe the model does not have, or a state of another model, before writing anything
  void reset_worlds(State& state, const std::vector<int>& worlds, int keyframe = -1, int threads = 0) const;
  // worlds `worlds` of `state` start afresh from the joint_q and joint_qd the state holds for them (written by the
  // caller: a start of its own, e.g. a random pose and velocity): as reset_worlds, with their coordinates and
  // velocities kept and each Free or Ball joint's quaternion normalised. Throws Error naming a world id out of range,
  // a coordinate or velocity that is not finite, or a quaternion of norm 0, before writing anything
  void restart_worlds(State& state, const std::vector<int>& worlds, int threads = 0) const;
  // a zeroed control with the model's PD gains (and keyframe `keyframe`'s actuator commands)
  Control control() const;
  Control control(const std::string& keyframe) const;
  // the index of the keyframe of that name; throws Error listing the model's keyframes when there is none
  int keyframe(const std::string& name) const;

  // per-world parameters at run time (engine/model/parameters.cpp): field `field`'s entries of worlds `worlds`
  // (each world's bodies, dofs, shapes or actuators in the model's order, or the world's own entry; `width`
  // numbers each) from `values`, world after world, checked first (finite; a moving body's mass positive and its
  // inertia a body's; gains, damping, armature, friction loss, stiffness and friction coefficients not negative;
  // lower ranges not above upper ones), then written, and the worlds marked changed. Throws Error naming the
  // field, world and item, writing nothing, for a field that is not a parameter, a world out of range, a wrong
  // count of values or a bad value. A solver reads the new values at its next step
  void set_parameter(const std::string& field, const std::vector<int>& worlds, const Scalar* values, size_t count);
  void set_parameter(const std::string& field, const std::vector<int>& worlds, const std::vector<Scalar>& values) {
    set_parameter(field, worlds, values.data(), values.size());
  }
  // the fields set_parameter writes, in its order
  static const std::vector<std::string>& parameter_names();
  // the entries of field `field` that world w's values go to, in order (its bodies, dofs, shapes or actuators, or
  // w itself); throws Error for a field that is not a parameter or a world out of range
  std::span<const int> parameter_entries(const std::string& field, int w) const;
  // each world's entries of each kind (bodies, dofs, shapes, actuators) listed once the layout is final (finalize)
  void index_parameters();
  // those fields copied from `other`, a model of the same bodies, dofs, shapes, actuators and worlds
  void copy_parameters(const Model& other);
  // the number of set_parameter calls so far, and per world the count when one last wrote into it (0: never): a
  // reader that has seen the values up to count n rereads the worlds whose entry is above n
  std::uint64_t parameter_writes = 0;
  std::vector<std::uint64_t> world_parameter_write;
  std::shared_ptr<const ParameterIndex> parameter_index;  // (index_parameters; copies of the model share it)

  // throws Error naming the array unless `state` / `control` was made for this model
  void check(const State& state) const;
  void check(const Control& control) const;
};

// body b's pose in the state (its frame in the world), the world frame for b = -1
inline Transform body_pose(const State& state, int b) {
  return b < 0 ? Transform::identity() : Transform::from_array(&state.body_q[7 * static_cast<size_t>(b)]);
}

}  // namespace novaphy
