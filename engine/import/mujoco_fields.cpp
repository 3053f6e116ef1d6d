#include "engine/import/mujoco_fields.h"

#include <cmath>
#include <cstring>

#include "engine/model/error.h"

namespace novaphy {

namespace {

// the largest value + 1 of each enumeration in any MuJoCo version read (MuJoCo 4's: it added to 2.2.2's lists)
constexpr int kJointTypes = 4, kGeomTypes = 9, kWrapTypes = 6, kTrnTypes = 7, kDynTypes = 8, kGainTypes = 7,
              kBiasTypes = 6, kEqTypes = 8;
// a joint type's coordinates and dofs: free, ball, slide, hinge
constexpr int kJointCoords[kJointTypes] = {7, 4, 1, 1}, kJointDofs[kJointTypes] = {6, 3, 1, 1};

// a value that is not finite as a file writes it: "nan" whatever its sign bit, "inf", "-inf"
const char* word(double x) { return std::isnan(x) ? "nan" : x > 0 ? "inf" : "-inf"; }

const char* kind_word(MjKind kind) {
  constexpr const char* words[] = {"body",     "joint",    "geom", "mesh",   "tendon",         "actuator",
                                   "keyframe", "equality", "site", "sensor", "plugin instance"};
  return words[static_cast<int>(kind)];
}

// the checks of one model; each message starts "MjModel field[i] (kind 'name')"
class FieldCheck {
 public:
  explicit FieldCheck(const MujocoFields& m) : m_(m) {}

  void run() {
    counts();
    names();
    bodies_and_joints();
    geoms_and_meshes();
    tendons();
    actuators();
    equalities();
    keyframes();
    sites_and_sensors();
  }

 private:
  std::string who(MjKind kind, int id) const {
    return std::string(" (") + kind_word(kind) + " '" + m_.name(kind, id) + "')";
  }

  // `column`: "[k]" for a field of several values per element
  void range(const char* field, int i, const std::string& who, int value, int lower, int upper,
             const char* column = "") const {
    if (value < lower || value >= upper)
      fail("MjModel ", field, "[", i, "]", column, who, ": ", value, " out of range [", lower, ", ", upper, ")");
  }

  // a field that must equal what the entries before it give
  void follows(const char* field, int i, const std::string& who, int value, int expected, const char* why) const {
    if (value != expected)
      fail("MjModel ", field, "[", i, "]", who, ": ", value, ", expected ", expected, " (", why, ")");
  }

  void finite(const char* field, int i, const std::string& who, const double* x, int width) const {
    for (int k = 0; k < width; ++k)
      if (!std::isfinite(x[k])) fail("MjModel ", field, "[", i, "][", k, "]", who, " is not finite: ", word(x[k]));
  }

  void quaternion(const char* field, int i, const std::string& who, const double* q) const {
    finite(field, i, who, q, 4);
    if (q[0] == 0 && q[1] == 0 && q[2] == 0 && q[3] == 0)
      fail("MjModel ", field, "[", i, "]", who, " is a zero quaternion");
  }

  void counts() const {
    const std::pair<const char*, int> counts[] = {{"nq", m_.nq},
                                                  {"nv", m_.nv},
                                                  {"nu", m_.nu},
                                                  {"nbody", m_.nbody},
                                                  {"njnt", m_.njnt},
                                                  {"ngeom", m_.ngeom},
                                                  {"ntendon", m_.ntendon},
                                                  {"nkey", m_.nkey},
                                                  {"neq", m_.neq},
                                                  {"nexclude", m_.nexclude},
                                                  {"nnames", m_.nnames},
                                                  {"nmesh", m_.nmesh},
                                                  {"nmeshvert", m_.nmeshvert},
                                                  {"nwrap", m_.nwrap},
                                                  {"nsite", m_.nsite},
                                                  {"nsensor", m_.nsensor}};
    for (const auto& [name, n] : counts)
      if (n < 0) fail("MjModel ", name, ": ", n, " is negative");
    if (m_.nbody < 1) fail("MjModel nbody: 0, expected at least the world body");
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(m_.gravity[k])) fail("MjModel opt.gravity[", k, "] is not finite: ", word(m_.gravity[k]));
  }

  // each name address inside names, a NUL after it
  void names() const {
    const std::pair<const int*, int> adr[] = {
        {m_.name_bodyadr, m_.nbody},     {m_.name_jntadr, m_.njnt},       {m_.name_geomadr, m_.ngeom},
        {m_.name_meshadr, m_.nmesh},     {m_.name_tendonadr, m_.ntendon}, {m_.name_actuatoradr, m_.nu},
        {m_.name_keyadr, m_.nkey},       {m_.name_eqadr, m_.neq},         {m_.name_siteadr, m_.nsite},
        {m_.name_sensoradr, m_.nsensor}, {m_.name_pluginadr, m_.nplugin}};
    constexpr const char* fields[] = {"name_bodyadr",   "name_jntadr",      "name_geomadr",  "name_meshadr",
                                      "name_tendonadr", "name_actuatoradr", "name_keyadr",   "name_eqadr",
                                      "name_siteadr",   "name_sensoradr",   "name_pluginadr"};
    for (int kind = 0; kind < 11; ++kind) {
      if (!adr[kind].first) continue;
      for (int id = 0; id < adr[kind].second; ++id) {
        const std::string who =
            std::string(" (") + kind_word(static_cast<MjKind>(kind)) + " " + std::to_string(id) + ")";
        const int at = adr[kind].first[id];
        range(fields[kind], id, who, at, 0, m_.nnames);
        if (!std::memchr(m_.names + at, '\0', m_.nnames - at))
          fail("MjModel ", fields[kind], "[", id, "]", who, ": the name at ", at,
               " has no NUL before the end of names (", m_.nnames, " bytes)");
      }
    }
  }

  // parents before children; each body's joints, and each joint's coordinates and dofs, after the previous ones
  void bodies_and_joints() const {
    range("body_jntnum", 0, who(MjKind::Body, 0), m_.body_jntnum[0], 0, 1);
    int joint = 0;
    for (int b = 1; b < m_.nbody; ++b) {
      const std::string body = who(MjKind::Body, b);
      range("body_parentid", b, body, m_.body_parentid[b], 0, b);
      range("body_jntnum", b, body, m_.body_jntnum[b], 0, m_.njnt - joint + 1);
      if (m_.body_jntnum[b] > 0) {
        range("body_jntadr", b, body, m_.body_jntadr[b], 0, m_.njnt);
        follows("body_jntadr", b, body, m_.body_jntadr[b], joint, "each body's joints follow the previous body's");
      }
      joint += m_.body_jntnum[b];
      finite("body_pos", b, body, m_.body_pos + 3 * b, 3);
      quaternion("body_quat", b, body, m_.body_quat + 4 * b);
      finite("body_ipos", b, body, m_.body_ipos + 3 * b, 3);
      quaternion("body_iquat", b, body, m_.body_iquat + 4 * b);
    }
    if (joint != m_.njnt) fail("MjModel njnt: ", m_.njnt, ", but the bodies hold ", joint, " joints (body_jntnum)");
    int q = 0, d = 0;
    for (int j = 0; j < m_.njnt; ++j) {
      const std::string name = who(MjKind::Joint, j);
      range("jnt_type", j, name, m_.jnt_type[j], 0, kJointTypes);
      range("jnt_qposadr", j, name, m_.jnt_qposadr[j], 0, m_.nq);
      follows("jnt_qposadr", j, name, m_.jnt_qposadr[j], q, "the joints' coordinates follow one another");
      range("jnt_dofadr", j, name, m_.jnt_dofadr[j], 0, m_.nv);
      follows("jnt_dofadr", j, name, m_.jnt_dofadr[j], d, "the joints' dofs follow one another");
      q += kJointCoords[m_.jnt_type[j]];
      d += kJointDofs[m_.jnt_type[j]];
      finite("jnt_pos", j, name, m_.jnt_pos + 3 * j, 3);
      const double* axis = m_.jnt_axis + 3 * j;
      finite("jnt_axis", j, name, axis, 3);
      if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0) fail("MjModel jnt_axis[", j, "]", name, " is a zero vector");
    }
    if (q != m_.nq) fail("MjModel nq: ", m_.nq, ", but the joints have ", q, " coordinates");
    if (d != m_.nv) fail("MjModel nv: ", m_.nv, ", but the joints have ", d, " dofs");
    for (int j = 0; j < m_.njnt; ++j)
      for (int i = m_.jnt_qposadr[j]; i < m_.jnt_qposadr[j] + kJointCoords[m_.jnt_type[j]]; ++i)
        if (!std::isfinite(m_.qpos0[i]))
          fail("MjModel qpos0[", i, "]", who(MjKind::Joint, j), " is not finite: ", word(m_.qpos0[i]));
  }

  void geoms_and_meshes() const {
    for (int g = 0; g < m_.ngeom; ++g) {
      const std::string geom = who(MjKind::Geom, g);
      range("geom_bodyid", g, geom, m_.geom_bodyid[g], 0, m_.nbody);
      range("geom_type", g, geom, m_.geom_type[g], 0, kGeomTypes);
      if (m_.geom_type[g] == mjGEOM_MESH) range("geom_dataid", g, geom, m_.geom_dataid[g], 0, m_.nmesh);
      finite("geom_pos", g, geom, m_.geom_pos + 3 * g, 3);
      quaternion("geom_quat", g, geom, m_.geom_quat + 4 * g);
    }
    for (int k = 0; k < m_.nmesh; ++k) {
      const std::string mesh = who(MjKind::Mesh, k);
      range("mesh_vertadr", k, mesh, m_.mesh_vertadr[k], 0, m_.nmeshvert);
      range("mesh_vertnum", k, mesh, m_.mesh_vertnum[k], 0, m_.nmeshvert - m_.mesh_vertadr[k] + 1);
    }
    for (int e = 0; e < m_.nexclude; ++e) {
      const int signature = m_.exclude_signature[e];
      range("exclude_signature", e, " (its first body)", (signature >> 16) - m_.exclude_body_offset, 0, m_.nbody);
      range("exclude_signature", e, " (its second body)", (signature & 0xffff) - m_.exclude_body_offset, 0, m_.nbody);
    }
  }

  void tendons() const {
    for (int t = 0; t < m_.ntendon; ++t) {
      const std::string tendon = who(MjKind::Tendon, t);
      range("tendon_adr", t, tendon, m_.tendon_adr[t], 0, m_.nwrap);
      range("tendon_num", t, tendon, m_.tendon_num[t], 0, m_.nwrap - m_.tendon_adr[t] + 1);
      for (int w = m_.tendon_adr[t]; w < m_.tendon_adr[t] + m_.tendon_num[t]; ++w) {
        range("wrap_type", w, tendon, m_.wrap_type[w], 0, kWrapTypes);
        const int type = m_.wrap_type[w];
        if (type == mjWRAP_JOINT) range("wrap_objid", w, tendon, m_.wrap_objid[w], 0, m_.njnt);
        if (type == mjWRAP_SITE) range("wrap_objid", w, tendon, m_.wrap_objid[w], 0, m_.nsite);
        if (type == mjWRAP_SPHERE || type == mjWRAP_CYLINDER) {
          range("wrap_objid", w, tendon, m_.wrap_objid[w], 0, m_.ngeom);
          range("wrap_prm", w, tendon + " (a side site)", static_cast<int>(std::lround(m_.wrap_prm[w])), -1, m_.nsite);
        }
      }
    }
  }

  void actuators() const {
    for (int u = 0; u < m_.nu; ++u) {
      const std::string actuator = who(MjKind::Actuator, u);
      range("actuator_trntype", u, actuator, m_.actuator_trntype[u], 0, kTrnTypes);
      range("actuator_dyntype", u, actuator, m_.actuator_dyntype[u], 0, kDynTypes);
      range("actuator_gaintype", u, actuator, m_.actuator_gaintype[u], 0, kGainTypes);
      range("actuator_biastype", u, actuator, m_.actuator_biastype[u], 0, kBiasTypes);
      const int type = m_.actuator_trntype[u];
      if (type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT)
        range("actuator_trnid", u, actuator, m_.actuator_trnid[2 * u], 0, m_.njnt, "[0]");
      if (type == mjTRN_TENDON) range("actuator_trnid", u, actuator, m_.actuator_trnid[2 * u], 0, m_.ntendon, "[0]");
      if (type == mjTRN_SITE) {
        range("actuator_trnid", u, actuator, m_.actuator_trnid[2 * u], 0, m_.nsite, "[0]");
        range("actuator_trnid", u, actuator, m_.actuator_trnid[2 * u + 1], -1, m_.nsite, "[1]");
      }
      if (m_.actuator_plugin) range("actuator_plugin", u, actuator, m_.actuator_plugin[u], -1, m_.nplugin);
    }
  }

  // the objects of the equalities the converter reads: bodies (connect, weld) and joints (joint)
  void equalities() const {
    for (int e = 0; e < m_.neq; ++e) {
      const std::string equality = who(MjKind::Equality, e);
      range("eq_type", e, equality, m_.eq_type[e], 0, kEqTypes);
      const int type = m_.eq_type[e];
      const bool bodies =
          (type == mjEQ_CONNECT || type == mjEQ_WELD) && (!m_.eq_objtype || m_.eq_objtype[e] == mjOBJ_BODY);
      const int count = bodies ? m_.nbody : type == mjEQ_JOINT ? m_.njnt : 0;
      if (count == 0) continue;
      range("eq_obj1id", e, equality, m_.eq_obj1id[e], 0, count);
      range("eq_obj2id", e, equality, m_.eq_obj2id[e], -1, count);
    }
  }

  // sites on bodies; each sensor's object in range for the object types the converter reads (2.2.2's numbering)
  void sites_and_sensors() const {
    for (int i = 0; i < m_.nsite; ++i) {
      const std::string site = who(MjKind::Site, i);
      range("site_bodyid", i, site, m_.site_bodyid[i], 0, m_.nbody);
      range("site_type", i, site, m_.site_type[i], 0, kGeomTypes);
      finite("site_pos", i, site, m_.site_pos + 3 * i, 3);
      quaternion("site_quat", i, site, m_.site_quat + 4 * i);
      finite("site_size", i, site, m_.site_size + 3 * i, 3);
    }
    for (int s = 0; s < m_.nsensor; ++s) {
      const std::string sensor = who(MjKind::Sensor, s);
      range("sensor_type", s, sensor, m_.sensor_type[s], -1, mjSENS_USER + 1);
      const std::pair<int, int> counts[] = {{mjOBJ_BODY, m_.nbody}, {mjOBJ_XBODY, m_.nbody}, {mjOBJ_JOINT, m_.njnt},
                                            {mjOBJ_GEOM, m_.ngeom}, {mjOBJ_SITE, m_.nsite},  {mjOBJ_TENDON, m_.ntendon},
                                            {mjOBJ_ACTUATOR, m_.nu}};
      for (const auto& [type, count] : counts)
        if (m_.sensor_objtype[s] == type) range("sensor_objid", s, sensor, m_.sensor_objid[s], 0, count);
      range("sensor_dim", s, sensor, m_.sensor_dim[s], 0, 1 << 20);
      if (!(m_.sensor_cutoff[s] >= 0))
        fail("MjModel sensor_cutoff[", s, "]", sensor, ": ", m_.sensor_cutoff[s], " is not >= 0");
    }
  }
  void keyframes() const {
    for (int k = 0; k < m_.nkey; ++k) {
      const std::string key = who(MjKind::Key, k);
      finite("key_qpos", k, key, m_.key_qpos + static_cast<size_t>(k) * m_.nq, m_.nq);
      finite("key_qvel", k, key, m_.key_qvel + static_cast<size_t>(k) * m_.nv, m_.nv);
      finite("key_ctrl", k, key, m_.key_ctrl + static_cast<size_t>(k) * m_.nu, m_.nu);
    }
  }

  const MujocoFields& m_;
};

}  // namespace

std::string MujocoFields::name(MjKind kind, int id) const {
  const int* adr[] = {name_bodyadr, name_jntadr, name_geomadr, name_meshadr,   name_tendonadr, name_actuatoradr,
                      name_keyadr,  name_eqadr,  name_siteadr, name_sensoradr, name_pluginadr};
  const int* at = adr[static_cast<int>(kind)];
  if (at && names && names[at[id]] != '\0') return names + at[id];
  return std::string(1, '#').append(std::to_string(id));
}

void check_mujoco_fields(const MujocoFields& m) { FieldCheck(m).run(); }

MujocoFields mujoco_fields(const mjModel* m) {
  MujocoFields f;
  f.nq = m->nq, f.nv = m->nv, f.nu = m->nu, f.nbody = m->nbody, f.njnt = m->njnt, f.ngeom = m->ngeom;
  f.ntendon = m->ntendon, f.nkey = m->nkey, f.neq = m->neq, f.nexclude = m->nexclude, f.npair = m->npair;
  f.nnames = m->nnames, f.nmesh = m->nmesh, f.nmeshvert = m->nmeshvert, f.nwrap = m->nwrap;
  f.gravity = m->opt.gravity;
  f.timestep = m->opt.timestep, f.impratio = m->opt.impratio, f.density = m->opt.density,
  f.viscosity = m->opt.viscosity;
  for (int k = 0; k < 3; ++k) f.wind[k] = m->opt.wind[k];
  f.clamp_ctrl = !(m->opt.disableflags & mjDSBL_CLAMPCTRL);
  f.filter_parent = !(m->opt.disableflags & mjDSBL_FILTERPARENT);
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
  f.jnt_solref = m->jnt_solref, f.jnt_solimp = m->jnt_solimp, f.jnt_margin = m->jnt_margin;
  f.dof_solref = m->dof_solref, f.dof_solimp = m->dof_solimp;
  f.tendon_solref_lim = m->tendon_solref_lim, f.tendon_solimp_lim = m->tendon_solimp_lim;
  f.tendon_solref_fri = m->tendon_solref_fri, f.tendon_solimp_fri = m->tendon_solimp_fri;
  f.tendon_margin = m->tendon_margin, f.eq_solref = m->eq_solref, f.eq_solimp = m->eq_solimp;
  f.geom_type = m->geom_type, f.geom_contype = m->geom_contype, f.geom_conaffinity = m->geom_conaffinity;
  f.geom_condim = m->geom_condim, f.geom_bodyid = m->geom_bodyid, f.geom_dataid = m->geom_dataid;
  f.geom_priority = m->geom_priority, f.geom_solmix = m->geom_solmix, f.geom_solref = m->geom_solref;
  f.geom_solimp = m->geom_solimp, f.geom_size = m->geom_size, f.geom_pos = m->geom_pos, f.geom_quat = m->geom_quat;
  f.geom_fluid = m->geom_fluid;
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
  f.nsite = m->nsite, f.nsensor = m->nsensor;
  f.name_siteadr = m->name_siteadr, f.name_sensoradr = m->name_sensoradr;
  f.site_type = m->site_type, f.site_bodyid = m->site_bodyid, f.site_size = m->site_size, f.site_pos = m->site_pos;
  f.site_quat = m->site_quat;
  f.sensor_type = m->sensor_type, f.sensor_objtype = m->sensor_objtype, f.sensor_objid = m->sensor_objid;
  f.sensor_refid = m->sensor_refid, f.sensor_dim = m->sensor_dim, f.sensor_adr = m->sensor_adr;
  f.sensor_cutoff = m->sensor_cutoff;
  return f;
}

}  // namespace novaphy
