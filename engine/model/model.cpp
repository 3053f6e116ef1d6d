#include "engine/model/model.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <functional>

#include "engine/model/body_kinematics.h"
#include "engine/model/error.h"
#include "engine/threads/parallel.h"

namespace novaphy {

const char* shape_type_name(ShapeType type) {
  switch (type) {
    case ShapeType::Plane: return "Plane";
    case ShapeType::Sphere: return "Sphere";
    case ShapeType::Box: return "Box";
    case ShapeType::Capsule: return "Capsule";
    case ShapeType::Cylinder: return "Cylinder";
    case ShapeType::Ellipsoid: return "Ellipsoid";
    case ShapeType::Mesh: return "Mesh";
  }
  return "Unknown";
}

const char* collision_filter_name(CollisionFilter filter) {
  switch (filter) {
    case CollisionFilter::GroupAndMask: return "GroupAndMask";
    case CollisionFilter::Mujoco: return "Mujoco";
  }
  return "unknown";
}

const char* friction_rule_name(FrictionRule rule) {
  switch (rule) {
    case FrictionRule::GeometricMean: return "GeometricMean";
    case FrictionRule::Mujoco: return "Mujoco";
  }
  return "unknown";
}

const char* precision_name(Precision precision) {
  switch (precision) {
    case Precision::Float64: return "float64";
    case Precision::Float32: return "float32";
  }
  return "unknown";
}

namespace {

struct SensorTypeInfo {
  const char* name;   // MJCF's
  const char* label;  // SensorType's
  int dim;
  SensorObject object;
};

constexpr SensorTypeInfo kSensorTypes[kSensorTypeCount] = {
    {"jointpos", "JointPos", 1, SensorObject::Joint},
    {"jointvel", "JointVel", 1, SensorObject::Joint},
    {"ballquat", "BallQuat", 4, SensorObject::Joint},
    {"ballangvel", "BallAngVel", 3, SensorObject::Joint},
    {"framepos", "FramePos", 3, SensorObject::Body},
    {"framequat", "FrameQuat", 4, SensorObject::Body},
    {"framexaxis", "FrameXAxis", 3, SensorObject::Body},
    {"frameyaxis", "FrameYAxis", 3, SensorObject::Body},
    {"framezaxis", "FrameZAxis", 3, SensorObject::Body},
    {"framelinvel", "FrameLinVel", 3, SensorObject::Body},
    {"frameangvel", "FrameAngVel", 3, SensorObject::Body},
    {"framelinacc", "FrameLinAcc", 3, SensorObject::Body},
    {"frameangacc", "FrameAngAcc", 3, SensorObject::Body},
    {"gyro", "Gyro", 3, SensorObject::Body},
    {"velocimeter", "Velocimeter", 3, SensorObject::Body},
    {"accelerometer", "Accelerometer", 3, SensorObject::Body},
    {"force", "Force", 3, SensorObject::Body},
    {"torque", "Torque", 3, SensorObject::Body},
    {"subtreecom", "SubtreeCom", 3, SensorObject::Body},
    {"touch", "Touch", 1, SensorObject::Body},
    {"contactforce", "ContactForce", 3, SensorObject::Body},
    {"projectedgravity", "ProjectedGravity", 3, SensorObject::Body},
    {"tendonpos", "TendonPos", 1, SensorObject::Tendon},
    {"tendonvel", "TendonVel", 1, SensorObject::Tendon},
};

const SensorTypeInfo& sensor_info(SensorType type) {
  const int t = static_cast<int>(type);
  if (t < 0 || t >= kSensorTypeCount) fail("sensor type ", t, " is not a SensorType (0 .. ", kSensorTypeCount - 1, ")");
  return kSensorTypes[t];
}

}  // namespace

const char* sensor_type_name(SensorType type) { return sensor_info(type).name; }
const char* sensor_type_label(SensorType type) { return sensor_info(type).label; }
int sensor_dim(SensorType type) { return sensor_info(type).dim; }
SensorObject sensor_object_kind(SensorType type) { return sensor_info(type).object; }

bool same_layout(const ModelCounts& a, const ModelCounts& b) {
  return a.world_count == b.world_count && a.body_count == b.body_count && a.joint_count == b.joint_count &&
         a.joint_coord_count == b.joint_coord_count && a.joint_dof_count == b.joint_dof_count &&
         a.articulation_count == b.articulation_count && a.shape_count == b.shape_count &&
         a.actuator_count == b.actuator_count && a.sensor_value_count == b.sensor_value_count;
}

namespace {

// the precision and layout `assign` needs of `other`
void check_assign(const ModelCounts& self, const ModelCounts& other, const char* what) {
  if (!same_layout(self, other))
    fail("assign: the other ", what, " belongs to a model with ", other.body_count, " bodies, ", other.joint_dof_count,
         " dofs and ", other.actuator_count, " actuators, this one to ", self.body_count, " bodies, ",
         self.joint_dof_count, " dofs and ", self.actuator_count);
  if (other.precision != self.precision)
    fail("assign: the other ", what, " is ", precision_name(other.precision), ", this one ",
         precision_name(self.precision));
}

// the copies of a call to from_float32 or to_float32: every field's entries converted (rounded to float or widened
// to double), all fields' in one parallel loop over chunks of them
class Conversions {
 public:
  template <typename To, typename From>
  void add(std::vector<To>& to, const std::vector<From>& from) {
    for (size_t begin = 0; begin < from.size(); begin += kChunk) {
      const size_t n = std::min(kChunk, from.size() - begin);
      chunks_.push_back([&to, &from, begin, n] {
        for (size_t i = begin; i < begin + n; ++i) to[i] = static_cast<To>(from[i]);
      });
    }
  }

  void run(int threads) const {
    const int count = static_cast<int>(chunks_.size());
    const int team = std::clamp(count, 1, threads > 0 ? threads : omp_get_max_threads());
    parallel_for(team, count, [&](int c) { chunks_[c](); });
  }

 private:
  static constexpr size_t kChunk = size_t{1} << 15;
  std::vector<std::function<void()>> chunks_;
};

}  // namespace

void State::assign(const State& other) {
  check_assign(*this, other, "state");
  *this = other;
}

void Control::assign(const Control& other) {
  check_assign(*this, other, "control");
  *this = other;
}

namespace {

// a State's or Control's fields into its float32 arrays (`rounding`) or from them, on `threads` threads
template <typename Owner>
void convert_float32(Owner& owner, bool rounding, int threads) {
  if (owner.precision != Precision::Float32) return;
  Conversions conversions;
#define NOVAPHY_CONVERT(T, name, count, width) \
  rounding ? conversions.add(owner.float32.name, owner.name) : conversions.add(owner.name, owner.float32.name);
  if constexpr (std::is_same_v<Owner, State>) {
    NOVAPHY_STATE_FIELDS(NOVAPHY_CONVERT)
  } else {
    NOVAPHY_CONTROL_FIELDS(NOVAPHY_CONVERT)
  }
#undef NOVAPHY_CONVERT
  conversions.run(threads);
}

}  // namespace

void State::from_float32(int threads) { convert_float32(*this, false, threads); }
void State::to_float32(int threads) { convert_float32(*this, true, threads); }
void Control::from_float32(int threads) { convert_float32(*this, false, threads); }
void Control::to_float32(int threads) { convert_float32(*this, true, threads); }

void Model::allocate() {
#define NOVAPHY_ALLOCATE(T, name, count, width) name.assign(static_cast<size_t>(count) * (width), T{});
  NOVAPHY_MODEL_FIELDS(NOVAPHY_ALLOCATE)
  world_parameter_write.assign(world_count, 0);
}

namespace {

// 64-bit words mixed into h (FNV-1a's prime over whole words; a tail shorter than a word padded with zeros)
void mix(std::uint64_t& h, const void* data, size_t bytes) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (size_t k = 0; k < bytes; k += 8) {
    std::uint64_t word = 0;
    std::memcpy(&word, p + k, std::min<size_t>(8, bytes - k));
    h = (h ^ word) * 0x100000001b3ull;
    h ^= h >> 29;
  }
  h = (h ^ bytes) * 0x100000001b3ull;
}

}  // namespace

void Model::set_model_id() {
  std::uint64_t h = 0xcbf29ce484222325ull;
  const ModelCounts& counts = *this;
  mix(h, &counts.world_count,
      offsetof(ModelCounts, sensor_value_count) + sizeof(int) - offsetof(ModelCounts, world_count));
  const int enums[] = {static_cast<int>(precision), static_cast<int>(collision_filter),
                       static_cast<int>(friction_rule)};
  mix(h, enums, sizeof(enums));
  mix(h, gravity.data(), sizeof(Scalar) * 3);
  mix(h, &impratio, sizeof(impratio));
  const Scalar fluid[] = {fluid_density, fluid_viscosity, wind[0], wind[1], wind[2]};
  mix(h, fluid, sizeof(fluid));
#define NOVAPHY_MIX_FIELD(T, name, count, width) mix(h, name.data(), name.size() * sizeof(T));
  NOVAPHY_MODEL_FIELDS(NOVAPHY_MIX_FIELD)
#undef NOVAPHY_MIX_FIELD
  model_id = h;
}

void Model::check_sizes() const {
#define NOVAPHY_CHECK_SIZE(T, name, count, width)          \
  if (name.size() != static_cast<size_t>(count) * (width)) \
    fail("model field " #name " has ", name.size(), " entries, expected ", static_cast<size_t>(count) * (width));
  NOVAPHY_MODEL_FIELDS(NOVAPHY_CHECK_SIZE)
}

ArticulationView Model::articulation(int a) const {
  if (a < 0 || a >= articulation_count) fail("articulation index ", a, " out of range [0, ", articulation_count, ")");
  ArticulationView art;
  art.joint_begin = articulation_start[a];
  art.joint_end = articulation_start[a + 1];
  art.joint_type = joint_type.data();
  art.joint_ancestor = joint_ancestor.data();
  art.joint_child = joint_child.data();
  art.joint_q_start = joint_q_start.data();
  art.joint_qd_start = joint_qd_start.data();
  art.joint_X_p = joint_X_p.data();
  art.joint_X_c = joint_X_c.data();
  art.joint_axis = joint_axis.data();
  art.joint_armature = joint_armature.data();
  art.joint_damping = joint_damping.data();
  art.joint_stiffness = joint_stiffness.data();
  art.joint_q_ref = joint_q_ref.data();
  art.body_mass = body_mass.data();
  art.body_com = body_com.data();
  art.body_inertia = body_inertia.data();
  art.world_gravity = world_gravity.data() + 3 * articulation_world(a);
  return art;
}

namespace {

// a state of `model` at the coordinates q and velocities qd (nullptr: zero), body_q and body_qd from FK
State state_at(const Model& model, const Scalar* q, const Scalar* qd) {
  State s;
  static_cast<ModelCounts&>(s) = model;
#define NOVAPHY_ALLOCATE_STATE(T, name, count, width) s.name.assign(static_cast<size_t>(model.count) * (width), T{});
  NOVAPHY_STATE_FIELDS(NOVAPHY_ALLOCATE_STATE)
#undef NOVAPHY_ALLOCATE_STATE
  std::copy_n(q, model.joint_coord_count, s.joint_q.begin());
  if (qd) std::copy_n(qd, model.joint_dof_count, s.joint_qd.begin());
  bodies_from_joints(model, s);
  if (model.precision == Precision::Float32) {
#define NOVAPHY_ALLOCATE_FLOAT32(T, name, count, width) s.float32.name.resize(s.name.size());
    NOVAPHY_STATE_FIELDS(NOVAPHY_ALLOCATE_FLOAT32)
    s.to_float32();
  }
  return s;
}

}  // namespace

int Model::tendon_world(int t) const {
  for (int e = tendon_path_start[t]; e < tendon_path_start[t + 1]; ++e)
    if (tendon_path_body[e] >= 0) return body_world[tendon_path_body[e]];
  const int dof = tendon_dof[tendon_start[t]];
  const int j =
      static_cast<int>(std::upper_bound(joint_qd_start.begin(), joint_qd_start.end(), dof) - joint_qd_start.begin()) -
      1;
  return body_world[joint_child[j]];
}

State Model::state() const { return state_at(*this, joint_q0.data(), nullptr); }

namespace {

// world ids as a mask of the model's worlds; throws naming `what` and an id out of range
std::vector<std::uint8_t> world_mask(const Model& model, const std::vector<int>& worlds, const char* what) {
  std::vector<std::uint8_t> mask(model.world_count, 0);
  for (size_t i = 0; i < worlds.size(); ++i) {
    if (worlds[i] < 0 || worlds[i] >= model.world_count)
      fail(what, ": worlds[", i, "] = ", worlds[i], " is not a world of the model (0 .. ", model.world_count - 1, ")");
    mask[worlds[i]] = 1;
  }
  return mask;
}

// where link j's quaternion starts in joint_q (a six-dof joint's after its position, a Ball joint's), -1: it has none
int quaternion_at(const ArticulationView& art, int j) {
  const int at = art.q_begin() + art.q_start(j);
  return joint_is_six_dof(art.type(j)) ? at + 3 : art.type(j) == JointType::Ball ? at : -1;
}

// the articulations of the worlds in `mask`
std::vector<int> articulations_of(const Model& model, const std::vector<std::uint8_t>& mask) {
  std::vector<int> arts;
  for (int a = 0; a < model.articulation_count; ++a) {
    const int w = model.articulation_world(a);
    if (w >= 0 && mask[w]) arts.push_back(a);
  }
  return arts;
}

// the worlds in `mask` start afresh (reset_worlds, restart_worlds), their articulations on `threads` threads: joint_q
// from q (nullptr: the state's own, each quaternion normalised) and joint_qd from qd (nullptr: zero; the state's
// own: kept), body_f zeroed, body_q and body_qd by FK, sensors zeroed, world_reset set
void start_worlds(const Model& model, State& state, const std::vector<std::uint8_t>& mask, const Scalar* q,
                  const Scalar* qd, int threads) {
  const std::vector<int> arts = articulations_of(model, mask);
  const int team = std::clamp(static_cast<int>(arts.size()), 1, threads > 0 ? threads : omp_get_max_threads());
  std::vector<ArticulationScratch> scratch(team);
  parallel_for(team, static_cast<int>(arts.size()), [&](int i) {
    const ArticulationView art = model.articulation(arts[i]);
    if (q) {
      std::copy_n(q + art.q_begin(), art.coord_count(), state.joint_q.begin() + art.q_begin());
    } else {
      for (int j = 0; j < art.link_count(); ++j)
        if (const int at = quaternion_at(art, j); at >= 0)
          Eigen::Map<Eigen::Matrix<Scalar, 4, 1>>(state.joint_q.data() + at).normalize();
    }
    if (qd != state.joint_qd.data())
      for (int k = art.qd_begin(); k < art.qd_begin() + art.dof_count(); ++k) state.joint_qd[k] = qd ? qd[k] : 0;
    for (int l = 0; l < art.link_count(); ++l) std::fill_n(state.body_f.begin() + 6 * art.body(l), 6, Scalar(0));
    ArticulationScratch& s = scratch[omp_get_thread_num()];
    store_body_state(kinematics(model, state, arts[i], s), s, state);
  });
  for (int w = 0; w < model.world_count; ++w) state.world_reset[w] |= mask[w];
  for (int s = 0; s < model.sensor_count; ++s)
    if (mask[model.sensor_world[s]])
      std::fill(state.sensor_data.begin() + model.sensor_start[s],
                state.sensor_data.begin() + model.sensor_start[s + 1], 0);
}

}  // namespace

void Model::reset_worlds(State& state, const std::vector<int>& worlds, int keyframe, int threads) const {
  check(state);
  if (keyframe < -1 || keyframe >= keyframe_count)
    fail("reset_worlds: keyframe ", keyframe, " is not one of the model's ", keyframe_count, " keyframes");
  const std::vector<std::uint8_t> mask = world_mask(*this, worlds, "reset_worlds");
  const Scalar* q =
      keyframe < 0 ? joint_q0.data() : keyframe_q.data() + static_cast<size_t>(keyframe) * joint_coord_count;
  const Scalar* qd = keyframe < 0 ? nullptr : keyframe_qd.data() + static_cast<size_t>(keyframe) * joint_dof_count;
  start_worlds(*this, state, mask, q, qd, threads);
}

void Model::restart_worlds(State& state, const std::vector<int>& worlds, int threads) const {
  check(state);
  const std::vector<std::uint8_t> mask = world_mask(*this, worlds, "restart_worlds");
  for (const int a : articulations_of(*this, mask)) {
    const ArticulationView art = articulation(a);
    const int w = articulation_world(a);
    for (int k = art.q_begin(); k < art.q_begin() + art.coord_count(); ++k)
      if (!std::isfinite(state.joint_q[k]))
        fail("restart_worlds: joint_q[", k, "] (world ", w, ") is not finite: ", state.joint_q[k]);
    for (int k = art.qd_begin(); k < art.qd_begin() + art.dof_count(); ++k)
      if (!std::isfinite(state.joint_qd[k]))
        fail("restart_worlds: joint_qd[", k, "] (world ", w, ") is not finite: ", state.joint_qd[k]);
    for (int j = 0; j < art.link_count(); ++j)
      if (const int at = quaternion_at(art, j);
          at >= 0 && Eigen::Map<const Eigen::Matrix<Scalar, 4, 1>>(state.joint_q.data() + at).squaredNorm() == 0)
        fail("restart_worlds: the quaternion joint_q[", at, ":", at + 4, "] of joint '",
             joint_name[art.joint_begin + j], "' (world ", w, ") is zero");
  }
  start_worlds(*this, state, mask, nullptr, state.joint_qd.data(), threads);
}

int Model::keyframe(const std::string& name) const {
  for (int k = 0; k < keyframe_count; ++k)
    if (keyframe_name[k] == name) return k;
  std::string names;
  for (const std::string& n : keyframe_name) names += (names.empty() ? "'" : ", '") + n + "'";
  fail("no keyframe '", name, "': the model has ", keyframe_count == 0 ? "none" : names);
}

State Model::state(const std::string& name) const {
  const int k = keyframe(name);
  return state_at(*this, keyframe_q.data() + static_cast<size_t>(k) * joint_coord_count,
                  keyframe_qd.data() + static_cast<size_t>(k) * joint_dof_count);
}

Control Model::control(const std::string& name) const {
  const int k = keyframe(name);
  Control c = control();
  std::copy_n(keyframe_ctrl.data() + static_cast<size_t>(k) * actuator_count, actuator_count, c.actuator_ctrl.begin());
  c.to_float32();
  return c;
}

Control Model::control() const {
  Control s;
  static_cast<ModelCounts&>(s) = *this;
#define NOVAPHY_ALLOCATE_MEMBER(T, name, count, width) s.name.assign(static_cast<size_t>(count) * (width), T{});
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_ALLOCATE_MEMBER)
#undef NOVAPHY_ALLOCATE_MEMBER
  s.joint_target_ke = joint_target_ke;
  s.joint_target_kd = joint_target_kd;
  if (precision == Precision::Float32) {
    NOVAPHY_CONTROL_FIELDS(NOVAPHY_ALLOCATE_FLOAT32)
#undef NOVAPHY_ALLOCATE_FLOAT32
    s.to_float32();
  }
  return s;
}

namespace {

void check_model_id(const Model& model, const ModelCounts& made_by, const char* what) {
  if (made_by.model_id != model.model_id)
    fail(what, " from another model: made by model ", std::hex, made_by.model_id, ", this is model ", model.model_id,
         " (make it with this model's ", what, "())");
}

// a Float32 state's or control's float32 arrays as long as its fields
template <typename Owner>
void check_float32(const Owner& owner, const char* what) {
  if (owner.precision == Precision::Float64) return;
#define NOVAPHY_CHECK_FLOAT32(T, name, count, width)  \
  if (owner.float32.name.size() != owner.name.size()) \
    fail(what, ": float32.", #name, " has ", owner.float32.name.size(), " entries, ", #name, " ", owner.name.size());
  if constexpr (std::is_same_v<Owner, State>) {
    NOVAPHY_STATE_FIELDS(NOVAPHY_CHECK_FLOAT32)
  } else {
    NOVAPHY_CONTROL_FIELDS(NOVAPHY_CHECK_FLOAT32)
  }
#undef NOVAPHY_CHECK_FLOAT32
}

}  // namespace

void Model::check(const State& state) const {
#define NOVAPHY_CHECK_ARRAY(T, name, count, width)                                                             \
  if (state.name.size() != static_cast<size_t>(count) * (width))                                               \
    fail(#name " has ", state.name.size(), " entries, the model needs ", static_cast<size_t>(count) * (width), \
         " (state or control from another model?)");
  NOVAPHY_STATE_FIELDS(NOVAPHY_CHECK_ARRAY)
  check_model_id(*this, state, "state");
  check_float32(state, "state");
}

void Model::check(const Control& control) const {
  const auto& state = control;
  NOVAPHY_CONTROL_FIELDS(NOVAPHY_CHECK_ARRAY)
  check_model_id(*this, control, "control");
  check_float32(control, "control");
}

}  // namespace novaphy
