// A compiled mujoco.MjModel of the user's own MuJoCo (PyPI 3.x or 4.x) read into the import's field view
// (engine/import/mujoco_fields.h) and converted by the same converter as add_mjcf; the state maps both ways.
#include <algorithm>
#include <cctype>
#include <initializer_list>
#include <optional>

#include "bindings/bindings.h"
#include "engine/import/mjcf_import.h"
#include "engine/model/error.h"

namespace novaphy::python {

namespace {

// the MjModel's arrays the view points into, kept alive while it converts
class MjModelFields {
 public:
  explicit MjModelFields(py::object m) : m_(std::move(m)) {
    for (auto [count, name] : {std::pair{&f_.nq, "nq"},
                               {&f_.nv, "nv"},
                               {&f_.nu, "nu"},
                               {&f_.nbody, "nbody"},
                               {&f_.njnt, "njnt"},
                               {&f_.ngeom, "ngeom"},
                               {&f_.ntendon, "ntendon"},
                               {&f_.nkey, "nkey"},
                               {&f_.neq, "neq"},
                               {&f_.nexclude, "nexclude"},
                               {&f_.npair, "npair"}})
      *count = size(name);
    const py::object opt = attr("opt");
    f_.gravity = array<double>(opt.attr("gravity"), "opt.gravity", 1, 3);
    f_.timestep = opt.attr("timestep").cast<double>();
    f_.impratio = opt.attr("impratio").cast<double>();
    f_.density = opt.attr("density").cast<double>();
    f_.viscosity = opt.attr("viscosity").cast<double>();
    const double* wind = array<double>(opt.attr("wind"), "opt.wind", 1, 3);
    std::copy_n(wind, 3, f_.wind);
    const py::object bits = py::module_::import("mujoco").attr("mjtDisableBit");
    const int disabled = opt.attr("disableflags").cast<int>();
    f_.clamp_ctrl = !(disabled & bits.attr("mjDSBL_CLAMPCTRL").cast<int>());
    f_.filter_parent = !(disabled & bits.attr("mjDSBL_FILTERPARENT").cast<int>());
    names_ = attr("names").cast<std::string>();
    f_.names = names_.c_str();
    f_.nnames = static_cast<int>(names_.size());
    read_names();
    read_bodies_and_joints();
    read_geoms();
    read_tendons_and_actuators();
    read_equalities();
    read_sites_and_sensors();
    for (auto [count, name] : {std::pair{&f_.nflex, "nflex"}, {&f_.nplugin, "nplugin"}})
      if (py::hasattr(m_, name)) *count = size(name);
    f_.actuator_plugin = newer_field<int>("actuator_plugin", f_.nu);
    f_.geom_fluid = newer_field<double>("geom_fluid", f_.ngeom, 12);
    f_.name_pluginadr = newer_field<int>("name_pluginadr", f_.nplugin);
  }
  const MujocoFields& fields() const { return f_; }

 private:
  py::object attr(const char* name) const {
    if (!py::hasattr(m_, name))
      fail("the MjModel has no field '", name, "' (NovaPhy reads compiled models of MuJoCo 3 and 4)");
    return m_.attr(name);
  }
  // a count (nq, nbody, ...): an int that fits a C int, not negative
  int size(const char* name) const {
    const py::object n = attr(name);
    int count = 0;
    try {
      count = n.cast<int>();
    } catch (const py::cast_error&) {
      fail("the MjModel's count '", name, "' is not an int of 32 bits: ", py::repr(n).cast<std::string>());
    }
    if (count < 0) fail("the MjModel's count '", name, "' is negative: ", count);
    return count;
  }
  // `name`'s data, which must hold count x width values of T (a copy where it is not C-contiguous)
  template <typename T>
  const T* array(py::handle value, const char* name, int count, int width) {
    const py::array a = py::array::ensure(value, py::array::c_style);
    const bool boolean = std::is_same_v<T, MjByte> && a && a.dtype().kind() == 'b';
    if (!a || (!boolean && !a.dtype().is(py::dtype::of<T>())) || a.size() != py::ssize_t{count} * width)
      fail("the MjModel's field '", name, "' is not ", count, " x ", width, " values of the type NovaPhy expects");
    keep_.push_back(a);
    return static_cast<const T*>(a.data());
  }
  template <typename T>
  const T* field(const char* name, int count, int width = 1) {
    return array<T>(attr(name), name, count, width);
  }
  // a field of MuJoCo >= 3 that an older compiled model lacks: null
  template <typename T>
  const T* newer_field(const char* name, int count, int width = 1) {
    return py::hasattr(m_, name) ? field<T>(name, count, width) : nullptr;
  }
  // a field whose width differs between versions: its data and width, one of `widths`
  template <typename T>
  const T* field_of_width(const char* name, int count, std::initializer_list<int> widths, int* width) {
    const py::array a = py::array::ensure(attr(name), py::array::c_style);
    *width = a && a.ndim() == 2 ? static_cast<int>(a.shape(1)) : count == 0 ? *widths.begin() : 1;
    if (std::find(widths.begin(), widths.end(), *width) == widths.end())
      fail("the MjModel's field '", name, "' has ", *width, " columns, which NovaPhy does not read");
    return field<T>(name, count, *width);
  }

  void read_names() {
    f_.name_bodyadr = field<int>("name_bodyadr", f_.nbody);
    f_.name_jntadr = field<int>("name_jntadr", f_.njnt);
    f_.name_geomadr = field<int>("name_geomadr", f_.ngeom);
    f_.nmesh = size("nmesh");
    f_.name_meshadr = field<int>("name_meshadr", f_.nmesh);
    f_.name_tendonadr = field<int>("name_tendonadr", f_.ntendon);
    f_.name_actuatoradr = field<int>("name_actuatoradr", f_.nu);
    f_.name_keyadr = field<int>("name_keyadr", f_.nkey);
    f_.name_eqadr = field<int>("name_eqadr", f_.neq);
  }

  void read_bodies_and_joints() {
    const int nb = f_.nbody, nj = f_.njnt;
    f_.qpos0 = field<double>("qpos0", f_.nq);
    f_.qpos_spring = field<double>("qpos_spring", f_.nq);
    f_.body_parentid = field<int>("body_parentid", nb);
    f_.body_jntnum = field<int>("body_jntnum", nb);
    f_.body_jntadr = field<int>("body_jntadr", nb);
    f_.body_pos = field<double>("body_pos", nb, 3);
    f_.body_quat = field<double>("body_quat", nb, 4);
    f_.body_mass = field<double>("body_mass", nb);
    f_.body_ipos = field<double>("body_ipos", nb, 3);
    f_.body_iquat = field<double>("body_iquat", nb, 4);
    f_.body_inertia = field<double>("body_inertia", nb, 3);
    f_.body_gravcomp = newer_field<double>("body_gravcomp", nb);
    f_.jnt_actgravcomp = newer_field<MjByte>("jnt_actgravcomp", nj);
    f_.jnt_type = field<int>("jnt_type", nj);
    f_.jnt_qposadr = field<int>("jnt_qposadr", nj);
    f_.jnt_dofadr = field<int>("jnt_dofadr", nj);
    f_.jnt_limited = field<MjByte>("jnt_limited", nj);
    f_.jnt_pos = field<double>("jnt_pos", nj, 3);
    f_.jnt_axis = field<double>("jnt_axis", nj, 3);
    f_.jnt_stiffness = field<double>("jnt_stiffness", nj);
    f_.jnt_range = field<double>("jnt_range", nj, 2);
    f_.jnt_actfrclimited = newer_field<MjByte>("jnt_actfrclimited", nj);
    f_.jnt_actfrcrange = newer_field<double>("jnt_actfrcrange", nj, 2);
    f_.dof_armature = field<double>("dof_armature", f_.nv);
    f_.dof_damping = field<double>("dof_damping", f_.nv);
    f_.dof_frictionloss = field<double>("dof_frictionloss", f_.nv);
    f_.jnt_solref = field<double>("jnt_solref", nj, mjNREF);
    f_.jnt_solimp = field<double>("jnt_solimp", nj, mjNIMP);
    f_.jnt_margin = field<double>("jnt_margin", nj);
    f_.dof_solref = field<double>("dof_solref", f_.nv, mjNREF);
    f_.dof_solimp = field<double>("dof_solimp", f_.nv, mjNIMP);
    f_.key_qpos = field<double>("key_qpos", f_.nkey, f_.nq);
    f_.key_qvel = field<double>("key_qvel", f_.nkey, f_.nv);
    f_.key_ctrl = field<double>("key_ctrl", f_.nkey, f_.nu);
  }

  void read_geoms() {
    const int ng = f_.ngeom;
    f_.geom_type = field<int>("geom_type", ng);
    f_.geom_contype = field<int>("geom_contype", ng);
    f_.geom_conaffinity = field<int>("geom_conaffinity", ng);
    f_.geom_condim = field<int>("geom_condim", ng);
    f_.geom_bodyid = field<int>("geom_bodyid", ng);
    f_.geom_dataid = field<int>("geom_dataid", ng);
    f_.geom_priority = field<int>("geom_priority", ng);
    f_.geom_solmix = field<double>("geom_solmix", ng);
    f_.geom_solref = field<double>("geom_solref", ng, mjNREF);
    f_.geom_solimp = field<double>("geom_solimp", ng, mjNIMP);
    f_.geom_size = field<double>("geom_size", ng, 3);
    f_.geom_pos = field<double>("geom_pos", ng, 3);
    f_.geom_quat = field<double>("geom_quat", ng, 4);
    f_.geom_friction = field<double>("geom_friction", ng, 3);
    f_.geom_margin = field<double>("geom_margin", ng);
    f_.geom_gap = field<double>("geom_gap", ng);
    f_.nmeshvert = size("nmeshvert");
    f_.mesh_vertadr = field<int>("mesh_vertadr", f_.nmesh);
    f_.mesh_vertnum = field<int>("mesh_vertnum", f_.nmesh);
    f_.mesh_vert = field<float>("mesh_vert", f_.nmeshvert, 3);
    f_.exclude_signature = field<int>("exclude_signature", f_.nexclude);
    if (f_.nexclude > 0) f_.exclude_body_offset = exclude_body_offset();
  }

  // how the user's MuJoCo writes an exclusion's bodies into exclude_signature (2.2.2 added 1 to each id, 4.0 does
  // not): asked of that MuJoCo, which compiles a model excluding bodies 1 and 2
  static int exclude_body_offset() {
    const py::object probe = py::module_::import("mujoco").attr("MjModel").attr("from_xml_string")(
        "<mujoco><worldbody><body name='a'><geom size='1'/></body><body name='b'><geom size='1'/></body>"
        "</worldbody><contact><exclude body1='a' body2='b'/></contact></mujoco>");
    const int signature = probe.attr("exclude_signature").cast<py::array_t<int>>().at(0);
    if (signature != (1 << 16 | 2) && signature != (2 << 16 | 3))
      fail("this MuJoCo writes the exclusion of bodies 1 and 2 as exclude_signature ", signature,
           ", which NovaPhy does not read");
    return (signature >> 16) - 1;
  }

  void read_tendons_and_actuators() {
    const int nt = f_.ntendon, nu = f_.nu;
    f_.tendon_adr = field<int>("tendon_adr", nt);
    f_.tendon_num = field<int>("tendon_num", nt);
    f_.tendon_limited = field<MjByte>("tendon_limited", nt);
    f_.tendon_range = field<double>("tendon_range", nt, 2);
    f_.tendon_stiffness = field<double>("tendon_stiffness", nt);
    f_.tendon_damping = field<double>("tendon_damping", nt);
    f_.tendon_frictionloss = field<double>("tendon_frictionloss", nt);
    f_.tendon_solref_lim = field<double>("tendon_solref_lim", nt, mjNREF);
    f_.tendon_solimp_lim = field<double>("tendon_solimp_lim", nt, mjNIMP);
    f_.tendon_solref_fri = field<double>("tendon_solref_fri", nt, mjNREF);
    f_.tendon_solimp_fri = field<double>("tendon_solimp_fri", nt, mjNIMP);
    f_.tendon_margin = field<double>("tendon_margin", nt);
    f_.tendon_lengthspring = field_of_width<double>("tendon_lengthspring", nt, {1, 2}, &f_.tendon_lengthspring_width);
    f_.tendon_armature = newer_field<double>("tendon_armature", nt);
    f_.nwrap = size("nwrap");
    f_.wrap_type = field<int>("wrap_type", f_.nwrap);
    f_.wrap_objid = field<int>("wrap_objid", f_.nwrap);
    f_.wrap_prm = field<double>("wrap_prm", f_.nwrap);
    f_.actuator_trntype = field<int>("actuator_trntype", nu);
    f_.actuator_dyntype = field<int>("actuator_dyntype", nu);
    f_.actuator_gaintype = field<int>("actuator_gaintype", nu);
    f_.actuator_biastype = field<int>("actuator_biastype", nu);
    f_.actuator_trnid = field<int>("actuator_trnid", nu, 2);
    f_.actuator_ctrllimited = field<MjByte>("actuator_ctrllimited", nu);
    f_.actuator_forcelimited = field<MjByte>("actuator_forcelimited", nu);
    f_.actuator_ctrlrange = field<double>("actuator_ctrlrange", nu, 2);
    f_.actuator_forcerange = field<double>("actuator_forcerange", nu, 2);
    f_.actuator_gear = field<double>("actuator_gear", nu, 6);
    f_.actuator_gainprm = field<double>("actuator_gainprm", nu, mjNGAIN);
    f_.actuator_biasprm = field<double>("actuator_biasprm", nu, mjNBIAS);
    f_.actuator_damping = newer_field<double>("actuator_damping", nu);
    f_.actuator_armature = newer_field<double>("actuator_armature", nu);
  }

  void read_equalities() {
    const int ne = f_.neq;
    f_.eq_type = field<int>("eq_type", ne);
    f_.eq_obj1id = field<int>("eq_obj1id", ne);
    f_.eq_obj2id = field<int>("eq_obj2id", ne);
    f_.eq_objtype = newer_field<int>("eq_objtype", ne);
    f_.eq_active = field<MjByte>(py::hasattr(m_, "eq_active0") ? "eq_active0" : "eq_active", ne);
    f_.eq_data = field_of_width<double>("eq_data", ne, {mjNEQDATA, mjNEQDATA + 1}, &f_.eq_data_width);
    f_.eq_solref = field<double>("eq_solref", ne, mjNREF);
    f_.eq_solimp = field<double>("eq_solimp", ne, mjNIMP);
  }

  // sensor types and object types by name in MuJoCo 2.2.2's numbering (the user's MuJoCo numbers them otherwise)
  void read_sites_and_sensors() {
    f_.nsite = size("nsite");
    f_.nsensor = size("nsensor");
    const int ns = f_.nsite, nn = f_.nsensor;
    f_.name_siteadr = field<int>("name_siteadr", ns);
    f_.name_sensoradr = field<int>("name_sensoradr", nn);
    f_.site_type = field<int>("site_type", ns);
    f_.site_bodyid = field<int>("site_bodyid", ns);
    f_.site_size = field<double>("site_size", ns, 3);
    f_.site_pos = field<double>("site_pos", ns, 3);
    f_.site_quat = field<double>("site_quat", ns, 4);
    const int* type = field<int>("sensor_type", nn);
    const int* objtype = field<int>("sensor_objtype", nn);
    f_.sensor_objid = field<int>("sensor_objid", nn);
    f_.sensor_refid = field<int>("sensor_refid", nn);
    f_.sensor_dim = field<int>("sensor_dim", nn);
    f_.sensor_adr = field<int>("sensor_adr", nn);
    f_.sensor_cutoff = field<double>("sensor_cutoff", nn);
    const py::module_ mujoco = py::module_::import("mujoco");
    const std::pair<const char*, int> objects[] = {{"mjOBJ_BODY", mjOBJ_BODY},        {"mjOBJ_XBODY", mjOBJ_XBODY},
                                                   {"mjOBJ_JOINT", mjOBJ_JOINT},      {"mjOBJ_GEOM", mjOBJ_GEOM},
                                                   {"mjOBJ_SITE", mjOBJ_SITE},        {"mjOBJ_TENDON", mjOBJ_TENDON},
                                                   {"mjOBJ_ACTUATOR", mjOBJ_ACTUATOR}};
    for (int i = 0; i < nn; ++i) {
      const std::string name = mujoco.attr("mjtSensor")(type[i]).attr("name").cast<std::string>();
      sensor_type_.push_back(mujoco_sensor_type(name));
      sensor_type_name_.push_back(name.rfind("mjSENS_", 0) == 0 ? lower(name.substr(7)) : name);
      const std::string object = mujoco.attr("mjtObj")(objtype[i]).attr("name").cast<std::string>();
      int value = -1;
      for (const auto& [n, v] : objects)
        if (object == n) value = v;
      sensor_objtype_.push_back(value);
    }
    f_.sensor_type = sensor_type_.data();
    f_.sensor_objtype = sensor_objtype_.data();
    f_.sensor_type_name = sensor_type_name_.data();
  }
  static std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  }

  py::object m_;
  MujocoFields f_;
  std::vector<int> sensor_type_, sensor_objtype_;
  std::vector<std::string> sensor_type_name_;
  std::string names_;
  std::vector<py::array> keep_;
};

void check_length(const Eigen::VectorXd& v, int length, const char* name) {
  if (v.size() != length) fail(name, " has ", v.size(), " entries; the imported model has ", length);
}

py::array_t<double> vector_array(const std::vector<double>& v) { return py::array_t<double>(v.size(), v.data()); }

}  // namespace

void bind_mujoco(py::module_& m) {
  auto builder = py::reinterpret_borrow<py::class_<ModelBuilder>>(m.attr("ModelBuilder"));
  py::class_<MujocoImport>(m, "MujocoImport",
                           "What add_mujoco_model made, and the maps between its MjModel's qpos / qvel and NovaPhy's "
                           "joint_q / joint_qd (the imported model's entries, from q_begin / qd_begin).")
      .def_readonly("warnings", &MujocoImport::warnings)
      .def_readonly("body_map", &MujocoImport::body_map, "MuJoCo body id -> NovaPhy body (-1: static).")
      .def_readonly("actuator_map", &MujocoImport::actuator_map, "MuJoCo actuator id -> NovaPhy actuator (-1: none).")
      .def_readonly("sensor_map", &MujocoImport::sensor_map,
                    "MuJoCo sensor id -> the builder's sensor (-1: not computed, named in the warnings).")
      .def_readonly("q_begin", &MujocoImport::q_begin)
      .def_readonly("qd_begin", &MujocoImport::qd_begin)
      .def(
          "to_joint_q",
          [](const MujocoImport& self, const Eigen::VectorXd& qpos) {
            check_length(qpos, self.nq, "qpos");
            std::vector<double> q(self.q_begin + self.nq);
            self.to_joint_q(qpos.data(), q.data());
            return vector_array({q.begin() + self.q_begin, q.end()});
          },
          py::arg("qpos"), "NovaPhy's joint_q of the imported joints from MuJoCo's qpos.")
      .def(
          "to_joint_qd",
          [](const MujocoImport& self, const Eigen::VectorXd& qpos, const Eigen::VectorXd& qvel) {
            check_length(qpos, self.nq, "qpos");
            check_length(qvel, self.nv, "qvel");
            std::vector<double> qd(self.qd_begin + self.nv);
            self.to_joint_qd(qpos.data(), qvel.data(), qd.data());
            return vector_array({qd.begin() + self.qd_begin, qd.end()});
          },
          py::arg("qpos"), py::arg("qvel"), "NovaPhy's joint_qd of the imported joints from MuJoCo's qpos and qvel.")
      .def(
          "to_qpos",
          [](const MujocoImport& self, const Eigen::VectorXd& joint_q) {
            check_length(joint_q, self.nq, "joint_q");
            std::vector<double> q(self.q_begin + self.nq), qpos(self.nq);
            std::copy(joint_q.data(), joint_q.data() + self.nq, q.begin() + self.q_begin);
            self.to_qpos(q.data(), qpos.data());
            return vector_array(qpos);
          },
          py::arg("joint_q"), "MuJoCo's qpos from NovaPhy's joint_q of the imported joints.")
      .def(
          "to_qvel",
          [](const MujocoImport& self, const Eigen::VectorXd& qpos, const Eigen::VectorXd& joint_qd) {
            check_length(qpos, self.nq, "qpos");
            check_length(joint_qd, self.nv, "joint_qd");
            std::vector<double> qd(self.qd_begin + self.nv), qvel(self.nv);
            std::copy(joint_qd.data(), joint_qd.data() + self.nv, qd.begin() + self.qd_begin);
            self.to_qvel(qpos.data(), qd.data(), qvel.data());
            return vector_array(qvel);
          },
          py::arg("qpos"), py::arg("joint_qd"), "MuJoCo's qvel from NovaPhy's joint_qd of the imported joints.");
  builder.def(
      "add_mujoco_model",
      [](ModelBuilder& self, py::object model, std::optional<Transform> xform, bool static_shapes) {
        ImportOptions options;
        options.xform = xform.value_or(Transform::identity());
        options.static_shapes = static_shapes;
        const MjModelFields fields(std::move(model));
        MujocoImport out = import_mujoco_fields(self, fields.fields(), options);
        const py::object warn = py::module_::import("warnings").attr("warn");
        for (const std::string& w : out.warnings) warn("novaphy: " + w, py::handle(PyExc_UserWarning), 2);
        return out;
      },
      py::arg("model"), py::kw_only(), py::arg("xform") = py::none(), py::arg("static_shapes") = true,
      "Imports a compiled mujoco.MjModel of the user's MuJoCo (3.x or 4.x from PyPI) with the converter add_mjcf "
      "uses; warns like add_mjcf and returns a MujocoImport (its warnings and the state maps).");
}

}  // namespace novaphy::python
