// The fields of a compiled MuJoCo model that the import reads (engine/import/mjcf_import.cpp), under mjModel's own
// names: a view over MuJoCo 2.2.2's mjModel (mujoco_fields below) or over a compiled model of another MuJoCo
// version (the Python binding fills it from a mujoco.MjModel's arrays). One converter reads either, so a file
// compiled by 2.2.2 and the same file compiled by today's MuJoCo build the same NovaPhy model.
// Enumerations (joint, geom, actuator, equality and wrap types) are MuJoCo's; their values agree from 2.2.2 to 4.
#pragma once

#include <mujoco/mujoco.h>

#include <string>

namespace novaphy {

using MjByte = unsigned char;  // MuJoCo's mjtByte, numpy's bool

enum class MjKind { Body, Joint, Geom, Mesh, Tendon, Actuator, Key, Equality, Site, Sensor, Plugin };

struct MujocoFields {
  int nq = 0, nv = 0, nu = 0, nbody = 0, njnt = 0, ngeom = 0, ntendon = 0, nkey = 0, neq = 0, nexclude = 0, npair = 0;
  int nnames = 0, nmesh = 0, nmeshvert = 0, nwrap = 0;  // the sizes of names, the mesh arrays, the wrap arrays
  int nsite = 0, nsensor = 0;
  // options
  const double *gravity = nullptr;  // [3]
  double timestep = 0.002, impratio = 1, density = 0, viscosity = 0, wind[3] = {0, 0, 0};
  bool clamp_ctrl = true;     // mjDSBL_CLAMPCTRL not set (its bit differs between versions)
  bool filter_parent = true;  // mjDSBL_FILTERPARENT not set

  // names: the null-terminated names at each kind's addresses; an empty one reads "#id"
  const char *names = nullptr;
  const int *name_bodyadr = nullptr, *name_jntadr = nullptr, *name_geomadr = nullptr, *name_meshadr = nullptr,
            *name_tendonadr = nullptr, *name_actuatoradr = nullptr, *name_keyadr = nullptr, *name_eqadr = nullptr,
            *name_siteadr = nullptr, *name_sensoradr = nullptr, *name_pluginadr = nullptr;

  const double *qpos0 = nullptr, *qpos_spring = nullptr;
  const int *body_parentid = nullptr, *body_jntnum = nullptr, *body_jntadr = nullptr;
  const double *body_pos = nullptr, *body_quat = nullptr, *body_mass = nullptr, *body_ipos = nullptr,
               *body_iquat = nullptr, *body_inertia = nullptr;
  const int *jnt_type = nullptr, *jnt_qposadr = nullptr, *jnt_dofadr = nullptr;
  const MjByte *jnt_limited = nullptr;
  const double *jnt_pos = nullptr, *jnt_axis = nullptr, *jnt_stiffness = nullptr, *jnt_range = nullptr;
  const double *dof_armature = nullptr, *dof_damping = nullptr, *dof_frictionloss = nullptr;
  // the softness of a joint's limits, a dof's dry friction, a tendon's limits and dry friction, an equality:
  // [mjNREF], [mjNIMP] each; a limit's margin
  const double *jnt_solref = nullptr, *jnt_solimp = nullptr, *jnt_margin = nullptr, *dof_solref = nullptr,
               *dof_solimp = nullptr, *tendon_solref_lim = nullptr, *tendon_solimp_lim = nullptr,
               *tendon_solref_fri = nullptr, *tendon_solimp_fri = nullptr, *tendon_margin = nullptr,
               *eq_solref = nullptr, *eq_solimp = nullptr;
  const int *geom_type = nullptr, *geom_contype = nullptr, *geom_conaffinity = nullptr, *geom_condim = nullptr,
            *geom_bodyid = nullptr, *geom_dataid = nullptr, *geom_priority = nullptr;
  const double *geom_solmix = nullptr, *geom_solref = nullptr, *geom_solimp = nullptr, *geom_size = nullptr,
               *geom_pos = nullptr, *geom_quat = nullptr, *geom_friction = nullptr, *geom_margin = nullptr,
               *geom_gap = nullptr;
  const int *mesh_vertadr = nullptr, *mesh_vertnum = nullptr;
  const float *mesh_vert = nullptr;
  const int *exclude_signature = nullptr;
  // exclude_signature holds (body1 + offset) << 16 | (body2 + offset): 1 in 2.2.2, 0 in today's MuJoCo
  int exclude_body_offset = 1;
  const int *tendon_adr = nullptr, *tendon_num = nullptr;
  const MjByte *tendon_limited = nullptr;
  const double *tendon_range = nullptr, *tendon_stiffness = nullptr, *tendon_damping = nullptr,
               *tendon_frictionloss = nullptr, *tendon_lengthspring = nullptr;
  int tendon_lengthspring_width = 1;  // 2.2.2: the spring's length; MuJoCo >= 3: its dead band [lower, upper]
  const int *wrap_type = nullptr, *wrap_objid = nullptr;
  const double *wrap_prm = nullptr;
  const int *actuator_trntype = nullptr, *actuator_dyntype = nullptr, *actuator_gaintype = nullptr,
            *actuator_biastype = nullptr, *actuator_trnid = nullptr;
  const MjByte *actuator_ctrllimited = nullptr, *actuator_forcelimited = nullptr;
  const double *actuator_ctrlrange = nullptr, *actuator_forcerange = nullptr, *actuator_gear = nullptr,
               *actuator_gainprm = nullptr, *actuator_biasprm = nullptr;
  const double *key_qpos = nullptr, *key_qvel = nullptr, *key_ctrl = nullptr;
  const int *site_type = nullptr, *site_bodyid = nullptr;
  const double *site_size = nullptr, *site_pos = nullptr, *site_quat = nullptr;
  // sensor_type and sensor_objtype in MuJoCo 2.2.2's numbering (mjtSensor, mjtObj), -1 for a type 2.2.2 lacks;
  // sensor_type_name: each sensor's type as the compiled model's MuJoCo names it (null: 2.2.2's own model)
  const int *sensor_type = nullptr, *sensor_objtype = nullptr, *sensor_objid = nullptr, *sensor_refid = nullptr,
            *sensor_dim = nullptr, *sensor_adr = nullptr;
  const double *sensor_cutoff = nullptr;
  const std::string *sensor_type_name = nullptr;
  const int *eq_type = nullptr, *eq_obj1id = nullptr, *eq_obj2id = nullptr;
  const MjByte *eq_active = nullptr;  // MuJoCo >= 3: eq_active0
  const double *eq_data = nullptr;
  int eq_data_width = mjNEQDATA;  // 11 in 2.2.2, 12 in MuJoCo 4 (the first 11 mean the same)

  // MuJoCo >= 3 only (null where the model has none): a joint's limit on its actuators' total force, the
  // objects an equality joins (bodies or sites), and what the import reports when it is not zero
  const MjByte *jnt_actfrclimited = nullptr, *jnt_actgravcomp = nullptr;
  const double *jnt_actfrcrange = nullptr;
  const int *eq_objtype = nullptr;
  const double *body_gravcomp = nullptr, *actuator_damping = nullptr, *actuator_armature = nullptr,
               *tendon_armature = nullptr;
  int nflex = 0, nplugin = 0;            // deformables and engine plugins (MuJoCo >= 3)
  const int *actuator_plugin = nullptr;  // the engine plugin instance that computes an actuator's force, or -1
  const double *geom_fluid = nullptr;    // [12 per geom]: MuJoCo's ellipsoid fluid model where [0] > 0

  // the name of object `id` of a kind, or "#id" for an unnamed one (its name address checked first)
  std::string name(MjKind kind, int id) const;
};

// throws Error where an index, address, count or type the converter reads is out of range or breaks MuJoCo's
// layout (each body's joints and each joint's coordinates and dofs follow the previous ones), where a frame, a
// quaternion or a keyframe value is not finite, and for a zero quaternion; the message names the field, the
// element and the value: "MjModel jnt_qposadr[3] (joint 'hip'): 99 out of range [0, 19)"
void check_mujoco_fields(const MujocoFields &m);

// a view over a MuJoCo 2.2.2 model (which must outlive it)
MujocoFields mujoco_fields(const mjModel *m);

}  // namespace novaphy
