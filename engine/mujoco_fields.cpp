#include "engine/mujoco_fields.h"

namespace novaphy {

std::string MujocoFields::name(MjKind kind, int id) const {
  const int* adr[] = {name_bodyadr,   name_jntadr,      name_geomadr, name_meshadr,
                      name_tendonadr, name_actuatoradr, name_keyadr,  name_eqadr};
  const int* at = adr[static_cast<int>(kind)];
  if (at && names && names[at[id]] != '\0') return names + at[id];
  return "#" + std::to_string(id);
}

MujocoFields mujoco_fields(const mjModel* m) {
  MujocoFields f;
  f.nq = m->nq, f.nv = m->nv, f.nu = m->nu, f.nbody = m->nbody, f.njnt = m->njnt, f.ngeom = m->ngeom;
  f.ntendon = m->ntendon, f.nkey = m->nkey, f.neq = m->neq, f.nexclude = m->nexclude, f.npair = m->npair;
  f.gravity = m->opt.gravity;
  f.timestep = m->opt.timestep, f.impratio = m->opt.impratio, f.density = m->opt.density,
  f.viscosity = m->opt.viscosity;
  f.clamp_ctrl = !(m->opt.disableflags & mjDSBL_CLAMPCTRL);
  f.names = m->names;
  f.name_bodyadr = m->name_bodyadr, f.name_jntadr = m->name_jntadr, f.name_geomadr = m->name_geomadr;
  f.name_meshadr = m->name_meshadr, f.name_tendonadr = m->name_tendonadr, f.name_actuatoradr = m->name_actuatoradr;
  f.name_keyadr = m->name_keyadr, f.name_eqadr = m->name_eqadr;
  f.qpos0 = m->qpos0, f.qpos_spring = m->qpos_spring;
  f.body_parentid = m->body_parentid, f.body_jntnum = m->body_jntnum, f.body_jntadr = m->body_jntadr;
  f.body_pos = m->body_pos, f.body_quat = m->body_quat, f.body_mass = m->body_mass, f.body_ipos = m->body_ipos;
  f.body_iquat = m->body_iquat, f.body_inertia = m->body_inertia;
  f.jnt_type = m->jnt_type, f.jnt_qposadr = m->jnt_qposadr, f.jnt_dofadr = m->jnt_dofadr;
  f.jnt_limited = m->jnt_limited, f.jnt_pos = m->jnt_pos, f.jnt_axis = m->jnt_axis;
  f.jnt_stiffness = m->jnt_stiffness, f.jnt_range = m->jnt_range;
  f.dof_armature = m->dof_armature, f.dof_damping = m->dof_damping, f.dof_frictionloss = m->dof_frictionloss;
  f.geom_type = m->geom_type, f.geom_contype = m->geom_contype, f.geom_conaffinity = m->geom_conaffinity;
  f.geom_condim = m->geom_condim, f.geom_bodyid = m->geom_bodyid, f.geom_dataid = m->geom_dataid;
  f.geom_priority = m->geom_priority, f.geom_solmix = m->geom_solmix, f.geom_solref = m->geom_solref;
  f.geom_solimp = m->geom_solimp, f.geom_size = m->geom_size, f.geom_pos = m->geom_pos, f.geom_quat = m->geom_quat;
  f.geom_friction = m->geom_friction, f.geom_margin = m->geom_margin, f.geom_gap = m->geom_gap;
  f.mesh_vertadr = m->mesh_vertadr, f.mesh_vertnum = m->mesh_vertnum, f.mesh_vert = m->mesh_vert;
  f.exclude_signature = m->exclude_signature;
  f.tendon_adr = m->tendon_adr, f.tendon_num = m->tendon_num, f.tendon_limited = m->tendon_limited;
  f.tendon_range = m->tendon_range, f.tendon_stiffness = m->tendon_stiffness, f.tendon_damping = m->tendon_damping;
  f.tendon_frictionloss = m->tendon_frictionloss, f.tendon_lengthspring = m->tendon_lengthspring;
  f.wrap_type = m->wrap_type, f.wrap_objid = m->wrap_objid, f.wrap_prm = m->wrap_prm;
  f.actuator_trntype = m->actuator_trntype, f.actuator_dyntype = m->actuator_dyntype;
  f.actuator_gaintype = m->actuator_gaintype, f.actuator_biastype = m->actuator_biastype;
  f.actuator_trnid = m->actuator_trnid, f.actuator_ctrllimited = m->actuator_ctrllimited;
  f.actuator_forcelimited = m->actuator_forcelimited, f.actuator_ctrlrange = m->actuator_ctrlrange;
  f.actuator_forcerange = m->actuator_forcerange, f.actuator_gear = m->actuator_gear;
  f.actuator_gainprm = m->actuator_gainprm, f.actuator_biasprm = m->actuator_biasprm;
  f.key_qpos = m->key_qpos, f.key_qvel = m->key_qvel, f.key_ctrl = m->key_ctrl;
  f.eq_type = m->eq_type, f.eq_obj1id = m->eq_obj1id, f.eq_obj2id = m->eq_obj2id, f.eq_active = m->eq_active;
  f.eq_data = m->eq_data;
  return f;
}

}  // namespace novaphy
