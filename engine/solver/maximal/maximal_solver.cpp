#include "engine/solver/maximal/maximal_solver.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "engine/model/actuator.h"
#include "engine/model/error.h"
#include "engine/model/finite_checks.h"
#include "engine/model/group_by_key.h"
#include "engine/solver/parts/applied_wrenches.h"
#include "engine/solver/step_arguments.h"
#include "kernels/joint.h"

namespace novaphy {

namespace {

// x rounded to float where the model steps in float32
void round_to_float(Scalar* x, int count) {
  for (int k = 0; k < count; ++k) x[k] = static_cast<float>(x[k]);
}

}  // namespace

MaximalSolver::MaximalSolver(const Model& model, const char* name)
    : model_(model), name_(name), step_name_(std::string(name) + ".step"), built_(MaximalConstraints::of(model, name)) {
  threads_ = std::max(1, omp_get_max_threads());
  next_.resize(model.body_count);
  body_slot_.assign(model.body_count, -1);
  for (int w = 0; w < model.world_count; ++w)
    for (int i = built_.body_start[w]; i < built_.body_start[w + 1]; ++i)
      body_slot_[built_.world_bodies[i]] = i - built_.body_start[w];
  dof_actuator_start_.resize(model.joint_dof_count + 1);
  dof_actuators_.resize(model.actuator_count);
  std::vector<int> next(std::max(model.joint_dof_count, model.world_count) + 1);
  group_by_key(
      model.actuator_count, model.joint_dof_count,
      [&](int u) { return model.actuator_joint[u] < 0 ? -1 : model.joint_qd_start[model.actuator_joint[u]]; },
      dof_actuator_start_.data(), dof_actuators_.data(), next.data());
  site_actuator_start_.resize(model.world_count + 1);
  site_actuators_.resize(model.actuator_count);
  group_by_key(
      model.actuator_count, model.world_count,
      [&](int u) { return model.actuator_body[u] < 0 ? -1 : model.body_world[model.actuator_body[u]]; },
      site_actuator_start_.data(), site_actuators_.data(), next.data());
  contact_start_.resize(model.world_count + 1);
  contact_next_.resize(model.world_count + 1);
  diverged_.assign(model.world_count, 0);
  for (int j = 0; j < model.joint_count; ++j) {
    Scalar armature = 0, friction = 0;
    for (int d = model.joint_qd_start[j]; d < model.joint_qd_start[j + 1]; ++d)
      armature = std::max(armature, model.joint_armature[d]),
      friction = std::max(friction, model.joint_frictionloss[d]);
    const std::string joint =
        "joint " + std::to_string(j) + (model.joint_name[j].empty() ? "" : " '" + model.joint_name[j] + "'");
    if (armature > 0) ignored_.push_back(joint + ": armature " + std::to_string(armature));
    if (friction > 0) ignored_.push_back(joint + ": frictionloss " + std::to_string(friction));
  }
  read_materials();
  read_masses();
}

void MaximalSolver::read_masses() {
  const int n = model_.body_count;
  inv_mass_.assign(n, 0);
  inertia_body_.assign(n, Mat3::Zero());
  inv_inertia_body_.assign(n, Mat3::Zero());
  for (int b = 0; b < n; ++b) {
    if (built_.body_static[b]) continue;
    const int of = built_.stand_in_of[b] >= 0 ? built_.stand_in_of[b] : b;
    const Scalar share = of == b ? 1 : MaximalConstraints::kStandInShare;
    const Eigen::Map<const Eigen::Matrix<Scalar, 3, 3, Eigen::RowMajor>> I(&model_.body_inertia[9 * of]);
    inv_mass_[b] = 1 / (share * model_.body_mass[of]);
    inertia_body_[b] = share * I;
    inv_inertia_body_[b] = inertia_body_[b].inverse();
  }
}

void MaximalSolver::read_materials() {
  const int n = model_.shape_count;
  materials_.resize(n);
  shape_material_.resize(n);
  shape_weight_.resize(n);
  for (int s = 0; s < n; ++s) {
    materials_[s] = contact_material(model_, s);
    shape_material_[s] = s;
    shape_weight_[s] = contact_weight(model_, s);
  }
  shapes_ = {materials_.data(), shape_material_.data(), shape_weight_.data(), nullptr, n, model_.friction_rule, 0};
  parameters_read_ = model_.parameter_writes;
}

void MaximalSolver::check_step(const State& in, const State& out, const Control& control, const Contacts& contacts,
                               Scalar dt) {
  if (!(dt > 0) || !std::isfinite(dt)) fail("dt must be finite and > 0, got ", dt);
  check_settings();
  check_step_arguments(model_, in, out, control, contacts, dt);
  Checked arrays[] = {{&in.body_q, "state_in.body_q"},
                      {&in.body_qd, "state_in.body_qd"},
                      {&in.body_f, "state_in.body_f"},
                      {&in.joint_q, "state_in.joint_q"},
                      {&control.joint_f, "control.joint_f"},
                      {&control.actuator_ctrl, "control.actuator_ctrl"},
                      {&control.joint_target_pos, "control.joint_target_pos"},
                      {&control.joint_target_vel, "control.joint_target_vel"},
                      {&control.joint_target_ke, "control.joint_target_ke"},
                      {&control.joint_target_kd, "control.joint_target_kd"}};
  check_finite(arrays, static_cast<int>(std::size(arrays)), thread_count());
  for (int d = 0; d < model_.joint_dof_count; ++d)
    if (control.joint_target_ke[d] < 0 || control.joint_target_kd[d] < 0)
      fail("control.joint_target_ke and joint_target_kd must be >= 0, got ", control.joint_target_ke[d], " and ",
           control.joint_target_kd[d], " at dof ", d);
}

void MaximalSolver::list_contacts(const Contacts& contacts) {
  // (a contact between two static shapes, which collide does not make, is no world's)
  auto world_of = [&](int c) {
    const int a = contacts.contact_body_a[c], b = contacts.contact_body_b[c];
    return a >= 0 ? model_.body_world[a] : b >= 0 ? model_.body_world[b] : -1;
  };
  if (static_cast<int>(world_contacts_.size()) < contacts.contact_count) world_contacts_.resize(contacts.contact_count);
  group_by_key(contacts.contact_count, model_.world_count, world_of, contact_start_.data(), world_contacts_.data(),
               contact_next_.data());
}

BodyMotion MaximalSolver::start_motion(const State& in, int b) const {
  BodyMotion m = BodyMotion::of(model_, in, b);
  if (b < 0 || built_.body_static[b]) {
    m.v.setZero(), m.w.setZero();
    return m;
  }
  m.inv_mass = inv_mass_[b];
  m.inv_inertia_body = inv_inertia_body_[b];
  m.orient();
  return m;
}

void MaximalSolver::forces(int w, const State& in, const Control& control, Scalar dt,
                           std::vector<BodyMotion>& bodies) const {
  const Vec3 g(model_.world_gravity[3 * w], model_.world_gravity[3 * w + 1], model_.world_gravity[3 * w + 2]);
  const int first = built_.body_start[w];
  for (size_t i = 0; i < bodies.size(); ++i) {
    BodyMotion& m = bodies[i];
    if (m.inv_mass == 0) continue;
    const int b = built_.world_bodies[first + i];
    const Scalar* f = &in.body_f[6 * static_cast<size_t>(b)];
    const Vec3 gyroscopic = -m.w.cross(m.q * (inertia_body_[b] * (m.q.conjugate() * m.w)));
    Vec3 force(f[0], f[1], f[2]), torque(f[3], f[4], f[5]);
    if (model_.body_gravcomp[b] != 0) force += gravity_compensation(model_, b);
    if (has_fluid(model_)) {
      Scalar fluid[6];
      fluid_wrench(model_, b, m.frame(model_, b), m.v, m.w, fluid);
      force += Vec3(fluid[0], fluid[1], fluid[2]);
      torque += Vec3(fluid[3], fluid[4], fluid[5]);
    }
    m.v += dt * (g + m.inv_mass * force);
    m.w += dt * (m.inv_inertia * (torque + gyroscopic));
  }
  for (int k = site_actuator_start_[w]; k < site_actuator_start_[w + 1]; ++k) {
    const int u = site_actuators_[k], b = model_.actuator_body[u];
    BodyMotion& m = bodies[body_slot_[b]];
    if (m.inv_mass == 0) continue;
    Scalar wrench[6];
    site_actuator_wrench(model_, u, control.actuator_ctrl[u], m.frame(model_, b), wrench);
    m.v += (dt * m.inv_mass) * Vec3(wrench[0], wrench[1], wrench[2]);
    m.w += dt * (m.inv_inertia * Vec3(wrench[3], wrench[4], wrench[5]));
  }
  for (int i = built_.joint_start[w]; i < built_.joint_start[w + 1]; ++i) {
    const int j = built_.world_joints[i];
    const auto type = static_cast<JointType>(model_.joint_type[j]);
    if (type != JointType::Free && type != JointType::Ball) continue;
    const Scalar* tau = &control.joint_f[model_.joint_qd_start[j]];
    const int parent = model_.joint_parent[j], child = model_.joint_child[j];
    BodyMotion& C = bodies[body_slot_[child]];
    BodyMotion* P = parent >= 0 ? &bodies[body_slot_[parent]] : nullptr;
    const Transform pj =
        (P ? P->frame(model_, parent) : Transform::identity()) * Transform::from_array(&model_.joint_X_p[7 * j]);
    const Transform cj = C.frame(model_, child) * Transform::from_array(&model_.joint_X_c[7 * j]);
    Vec3 torque, force = Vec3::Zero();
    if (type == JointType::Free) {  // [torque; force] in the parent joint frame, the force at the child's origin
      torque = pj.q * Vec3(tau[0], tau[1], tau[2]);
      force = pj.q * Vec3(tau[3], tau[4], tau[5]);
    } else {  // a torque in the child joint frame
      torque = cj.q * Vec3(tau[0], tau[1], tau[2]);
    }
    C.v += (dt * C.inv_mass) * force;
    C.w += dt * (C.inv_inertia * (torque + (cj.p - C.x).cross(force)));
    if (P) P->w -= dt * (P->inv_inertia * torque);
  }
}

Scalar MaximalSolver::axis_coordinate(const MaximalConstraint& c, int k, const State& in, Scalar coordinate) const {
  if (c.joint < 0) return coordinate;
  const auto type = static_cast<JointType>(model_.joint_type[c.joint]);
  if ((type == JointType::Revolute && k == 0) || (type == JointType::Prismatic && k == 3))
    return in.joint_q[model_.joint_q_start[c.joint]];
  return coordinate;
}

AxisSpring MaximalSolver::axis_spring(const MaximalConstraint& c, int k, const State& in,
                                      const Control& control) const {
  AxisSpring s;
  const int d = c.dof[k];
  if (d < 0) return s;
  const Scalar ke = control.joint_target_ke[d], kd = control.joint_target_kd[d];
  s.pull = ke * control.joint_target_pos[d];
  s.force = control.joint_f[d] + kd * control.joint_target_vel[d];
  s.stiffness = ke;
  s.damping = kd + model_.joint_damping[d];
  const auto type = static_cast<JointType>(model_.joint_type[c.joint]);
  if (type == JointType::Revolute || type == JointType::Prismatic) {
    const int q = model_.joint_q_start[c.joint];
    s.pull += model_.joint_stiffness[d] * model_.joint_q_ref[q];
    s.stiffness += model_.joint_stiffness[d];
    for (int i = dof_actuator_start_[d]; i < dof_actuator_start_[d + 1]; ++i) {
      const int u = dof_actuators_[i];
      const ActuatorForce a = actuator_force(model_, u, control.actuator_ctrl[u], in.joint_q[q], in.joint_qd[d]);
      (a.stiffness > 0 ? s.pull : s.force) += a.force;
      s.stiffness += a.stiffness;
      s.damping += a.damping;
    }
  } else {
    s.stiffness += model_.joint_stiffness[d];
  }
  return s;
}

bool MaximalSolver::world_diverged(int w, const Contacts& contacts, const GuardSettings& guard) const {
  for (int i = built_.body_start[w]; i < built_.body_start[w + 1]; ++i) {
    const int b = built_.world_bodies[i];
    if (built_.body_static[b]) continue;
    const BodyMotion& m = next_[b];
    if (!m.x.allFinite() || !m.q.coeffs().allFinite() || !m.v.allFinite() || !m.w.allFinite()) return true;
    if (m.v.norm() > guard.speed || m.w.norm() > guard.speed) return true;
  }
  int count = 0;
  const int* list = contacts_of(w, &count);
  for (int i = 0; i < count; ++i)
    if (contacts.contact_depth[list[i]] > guard.depth) return true;
  return false;
}

void MaximalSolver::write_world(int w, const State& in, State& out) const {
  const bool diverged = diverged_[w] != 0;
  for (int i = built_.joint_start[w]; i < built_.joint_start[w + 1]; ++i) {
    const int j = built_.world_joints[i];
    if (&in != &out) {
      std::copy_n(&in.joint_q[model_.joint_q_start[j]], model_.joint_q_start[j + 1] - model_.joint_q_start[j],
                  &out.joint_q[model_.joint_q_start[j]]);
      std::copy_n(&in.joint_qd[model_.joint_qd_start[j]], model_.joint_qd_start[j + 1] - model_.joint_qd_start[j],
                  &out.joint_qd[model_.joint_qd_start[j]]);
    }
  }
  const bool float32 = model_.precision == Precision::Float32;
  for (int i = built_.body_start[w]; i < built_.body_start[w + 1]; ++i) {
    const int b = built_.world_bodies[i];
    const size_t at = static_cast<size_t>(b);
    if (&in != &out) {
      std::copy_n(&in.body_f[6 * at], 6, &out.body_f[6 * at]);
      if (diverged || built_.body_static[b]) {
        std::copy_n(&in.body_q[7 * at], 7, &out.body_q[7 * at]);
        std::copy_n(&in.body_qd[6 * at], 6, &out.body_qd[6 * at]);
      }
    }
    if (diverged || built_.body_static[b]) continue;
    next_[b].store(model_, b, out);
    if (float32) round_to_float(&out.body_q[7 * at], 7), round_to_float(&out.body_qd[6 * at], 6);
  }
  out.world_reset[w] = 0;
  if (diverged) return;
  built_.joint_coordinates(model_, out, w);
  if (!float32) return;
  for (int i = built_.joint_start[w]; i < built_.joint_start[w + 1]; ++i) {
    const int j = built_.world_joints[i];
    round_to_float(&out.joint_q[model_.joint_q_start[j]], model_.joint_q_start[j + 1] - model_.joint_q_start[j]);
    round_to_float(&out.joint_qd[model_.joint_qd_start[j]], model_.joint_qd_start[j + 1] - model_.joint_qd_start[j]);
  }
}

void MaximalSolver::step(const State& in, State& out, const Control& control, Contacts& contacts, Scalar dt) {
  const ExclusiveCall call(busy_, step_name_.c_str());
  check_step(in, out, control, contacts, dt);
  if (model_.parameter_writes != parameters_read_) read_materials(), read_masses();
  shapes_.dt = dt;
  list_contacts(contacts);
  const GuardSettings guard = guard_settings();
  // (no more threads than worlds: a parallel region of idle threads costs more than a small world's step)
  const int threads = std::clamp(thread_count() == 0 ? omp_get_max_threads() : thread_count(), 1,
                                 std::min(threads_, model_.world_count));
  const StepInput step{in, control, contacts, dt};
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int w = 0; w < model_.world_count; ++w) {
    step_world(w, step, omp_get_thread_num());
    diverged_[w] = world_diverged(w, contacts, guard);
  }
  const auto first = std::find(diverged_.begin(), diverged_.end(), 1);
  if (guard.on_divergence == DivergencePolicy::Raise && first != diverged_.end())
    fail(name_, ": world ", first - diverged_.begin(),
         " diverged (a body's state went non-finite or beyond settings.divergence_speed, or a contact deeper than "
         "settings.divergence_depth); nothing was written");
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int w = 0; w < model_.world_count; ++w) write_world(w, in, out);
  if (guard.on_divergence != DivergencePolicy::Reset || first == diverged_.end()) return;
  std::vector<int> reset;
  for (int w = 0; w < model_.world_count; ++w)
    if (diverged_[w]) reset.push_back(w);
  model_.reset_worlds(out, reset, -1, threads);
}

}  // namespace novaphy
