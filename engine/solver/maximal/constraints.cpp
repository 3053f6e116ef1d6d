#include "engine/solver/maximal/constraints.h"

#include <cmath>

#include "engine/model/error.h"
#include "engine/model/group_by_key.h"
#include "engine/solver/parts/equality_rows.h"
#include "kernels/joint.h"

namespace novaphy {

namespace {

constexpr Scalar kPi = 3.14159265358979323846;

// the rotation taking x to the unit vector `axis` (a Revolute or Prismatic joint's frame turned so its axis is x)
Quat x_to(const Vec3& axis) { return Quat::FromTwoVectors(Vec3::UnitX(), axis).normalized(); }

// an axis's mode from its range: locked where the range is one value, free where it is unbounded
AxisMode mode_of(Scalar lower, Scalar upper) {
  if (lower == upper) return AxisMode::Locked;
  return std::isfinite(lower) || std::isfinite(upper) ? AxisMode::Limited : AxisMode::Free;
}

// joint j's constraint (false: it holds nothing, a Free joint's or a Fixed joint of a static body)
bool joint_constraint(const Model& model, int j, const std::vector<std::uint8_t>& body_static, MaximalConstraint& c) {
  const auto type = static_cast<JointType>(model.joint_type[j]);
  const int dof = model.joint_qd_start[j];
  c.joint = j;
  c.a = model.joint_parent[j];
  c.b = model.joint_child[j];
  c.world = model.body_world[c.b];
  c.X_a = Transform::from_array(&model.joint_X_p[7 * j]);
  c.X_b = Transform::from_array(&model.joint_X_c[7 * j]);
  c.compliance[0] = model.joint_compliance[2 * j];
  c.compliance[1] = model.joint_compliance[2 * j + 1];
  for (int k = 0; k < 6; ++k) c.mode[k] = AxisMode::Locked;
  auto range = [&](int k, int d) {
    c.lower[k] = model.joint_limit_lower[d];
    c.upper[k] = model.joint_limit_upper[d];
    c.mode[k] = mode_of(c.lower[k], c.upper[k]);
    c.dof[k] = d;
  };
  switch (type) {
    case JointType::Free: return false;
    case JointType::Fixed: return !body_static[c.b];
    case JointType::Revolute:
    case JointType::Prismatic: {
      const Quat turn = x_to(Vec3(model.joint_axis[3 * j], model.joint_axis[3 * j + 1], model.joint_axis[3 * j + 2]));
      c.X_a.q = (c.X_a.q * turn).normalized();
      c.X_b.q = (c.X_b.q * turn).normalized();
      range(type == JointType::Revolute ? 0 : 3, dof);
      return true;
    }
    case JointType::Ball:
      for (int k = 0; k < 3; ++k) c.mode[k] = AxisMode::Free;
      return true;
    case JointType::Distance:
      c.distance = true;
      for (int k = 0; k < 6; ++k) c.mode[k] = AxisMode::Free;
      c.lower[3] = model.joint_limit_lower[dof];
      c.upper[3] = model.joint_limit_upper[dof];
      c.mode[3] = AxisMode::Limited;
      return true;
    case JointType::D6:
      for (int k = 0; k < 6; ++k) range(k, dof + k);
      return true;
    case JointType::Cable: return true;
  }
  return false;
}

}  // namespace

Vec3 rotation_vector(const Quat& q) {
  const Quat u = q.w() < 0 ? Quat(-q.w(), -q.x(), -q.y(), -q.z()) : q;
  const Vec3 v = u.vec();
  const Scalar s = v.norm();
  if (s < 1e-12) return 2 * v;
  return (2 * std::atan2(s, u.w()) / s) * v;
}

Quat turned(const Quat& q, const Vec3& r) {
  const Scalar angle = r.norm();
  const Quat e =
      angle < 1e-12 ? Quat(1, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z()) : Quat(Eigen::AngleAxis<Scalar>(angle, r / angle));
  return (e * q).normalized();
}

Quat turned_slightly(const Quat& q, const Vec3& r) {
  const Quat e(0, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z());
  Quat out = e * q;
  out.coeffs() += q.coeffs();
  return out.normalized();
}

MaximalConstraints MaximalConstraints::of(const Model& model, const std::string& solver) {
  if (model.tendon_count > 0)
    fail(solver, " does not model tendons (tendon 0 '", model.tendon_name[0], "'): use SolverFeatherstone");
  if (model.sensor_count > 0)
    fail(solver, " does not compute sensors (sensor 0 '", model.sensor_name[0], "'): use SolverFeatherstone");
  MaximalConstraints out;
  // bodies held to the world by Fixed joints do not move
  out.body_static.assign(model.body_count, 0);
  for (int j = 0; j < model.joint_count; ++j) {
    const int parent = model.joint_parent[j];
    if (static_cast<JointType>(model.joint_type[j]) == JointType::Fixed && (parent < 0 || out.body_static[parent]))
      out.body_static[model.joint_child[j]] = 1;
  }
  // a moving body of no mass takes a share of the nearest body of mass below it along its chain
  std::vector<int> child_of(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j)
    if (model.joint_parent[j] >= 0 && child_of[model.joint_parent[j]] < 0)
      child_of[model.joint_parent[j]] = model.joint_child[j];
  out.stand_in_of.assign(model.body_count, -1);
  for (int b = 0; b < model.body_count; ++b) {
    if (out.body_static[b] || model.body_mass[b] > 0) continue;
    int below = child_of[b];
    while (below >= 0 && !(model.body_mass[below] > 0)) below = child_of[below];
    if (below < 0)
      fail(solver, " needs every moving body to have a mass or one of mass below it: body ", b,
           model.body_name[b].empty() ? "" : " '" + model.body_name[b] + "'", " has ", model.body_mass[b]);
    out.stand_in_of[b] = below;
  }

  std::vector<std::vector<MaximalConstraint>> by_world(model.world_count);
  for (int j = 0; j < model.joint_count; ++j) {
    MaximalConstraint c;
    if (joint_constraint(model, j, out.body_static, c)) by_world[c.world].push_back(c);
  }
  for (int e = 0; e < model.equality_count; ++e) {
    const auto type = static_cast<EqualityType>(model.equality_type[e]);
    const std::string& name = model.equality_name[e];
    if (type == EqualityType::JointCoupling)
      fail(solver, " does not model joint couplings (equality ", e, name.empty() ? "" : " '" + name + "'",
           "): use SolverFeatherstone");
    const BodyEquality eq = BodyEquality::of(model, e);
    MaximalConstraint c;
    c.equality = e;
    c.a = model.equality_object[2 * e];
    c.b = model.equality_object[2 * e + 1];
    c.world = model.body_world[c.a >= 0 ? c.a : c.b];
    c.X_a.p = eq.anchor1;
    c.X_b.p = eq.anchor2;
    for (int k = 0; k < 6; ++k) c.mode[k] = AxisMode::Locked;
    if (type == EqualityType::Weld)
      c.X_a.q = eq.relative;
    else
      for (int k = 0; k < 3; ++k) c.mode[k] = AxisMode::Free;
    by_world[c.world].push_back(c);
  }
  out.world_start.assign(1, 0);
  for (const auto& list : by_world) {
    out.constraints.insert(out.constraints.end(), list.begin(), list.end());
    out.world_start.push_back(static_cast<int>(out.constraints.size()));
  }
  auto group = [&](int count, auto world_of, std::vector<int>& items, std::vector<int>& start) {
    start.resize(model.world_count + 1);
    items.resize(count);
    std::vector<int> next(model.world_count + 1);
    group_by_key(count, model.world_count, world_of, start.data(), items.data(), next.data());
  };
  group(
      model.body_count, [&](int b) { return model.body_world[b]; }, out.world_bodies, out.body_start);
  group(
      model.joint_count, [&](int j) { return model.body_world[model.joint_child[j]]; }, out.world_joints,
      out.joint_start);
  return out;
}

BodyMotion BodyMotion::of(const Model& model, const State& state, int b) {
  BodyMotion m;
  if (b < 0) return m;
  const Scalar* X = &state.body_q[7 * static_cast<size_t>(b)];
  const Scalar* V = &state.body_qd[6 * static_cast<size_t>(b)];
  m.q = Quat(X[6], X[3], X[4], X[5]).normalized();
  m.x =
      Vec3(X[0], X[1], X[2]) + m.q * Vec3(model.body_com[3 * b], model.body_com[3 * b + 1], model.body_com[3 * b + 2]);
  m.v = Vec3(V[0], V[1], V[2]);
  m.w = Vec3(V[3], V[4], V[5]);
  return m;
}

Transform BodyMotion::frame(const Model& model, int b) const {
  Transform t;
  t.q = q;
  t.p = x - q * Vec3(model.body_com[3 * b], model.body_com[3 * b + 1], model.body_com[3 * b + 2]);
  return t;
}

void BodyMotion::store(const Model& model, int b, State& state) const {
  frame(model, b).to_array(&state.body_q[7 * static_cast<size_t>(b)]);
  Scalar* V = &state.body_qd[6 * static_cast<size_t>(b)];
  for (int k = 0; k < 3; ++k) V[k] = v[k], V[3 + k] = w[k];
}

void constraint_coordinates(const MaximalConstraint& c, const Transform& frame_a, const Transform& frame_b,
                            Scalar coordinate[6]) {
  const Transform rel = frame_a.inverse() * frame_b;
  for (int k = 0; k < 3; ++k) coordinate[3 + k] = rel.p[k];
  if (c.distance) coordinate[3] = (frame_b.p - frame_a.p).norm();
  int turning = -1, count = 0;
  for (int k = 0; k < 3; ++k)
    if (c.mode[k] != AxisMode::Locked) turning = k, ++count;
  Vec3 angle;
  if (count == 1) {
    // one axis turns (a hinge): the rotation as a swing after a twist about it, the twist's angle its coordinate (any
    // angle) and the swing's rotation vector the others' (exact at any twist, where the rotation vector's components
    // mix as the twist nears pi)
    const Quat& q = rel.q;
    const Scalar along = q.vec()[turning];
    const Scalar norm = std::hypot(along, q.w());
    Quat twist = Quat::Identity();
    if (norm > 1e-12) {
      twist.w() = q.w() / norm;
      twist.vec() = Vec3::Unit(turning) * (along / norm);
    }
    angle = rotation_vector(q * twist.conjugate());
    angle[turning] = std::remainder(2 * std::atan2(along, q.w()), 2 * kPi);
  } else {
    angle = rotation_vector(rel.q);
  }
  for (int k = 0; k < 3; ++k) coordinate[k] = angle[k];
}

void MaximalConstraints::joint_coordinates(const Model& model, State& state, int w) const {
  for (int i = joint_start[w]; i < joint_start[w + 1]; ++i) {
    const int j = world_joints[i];
    const auto type = static_cast<JointType>(model.joint_type[j]);
    const int parent = model.joint_parent[j], child = model.joint_child[j];
    const BodyMotion P = BodyMotion::of(model, state, parent), C = BodyMotion::of(model, state, child);
    const Transform pj =
        (parent < 0 ? Transform::identity() : P.frame(model, parent)) * Transform::from_array(&model.joint_X_p[7 * j]);
    const Transform cj = C.frame(model, child) * Transform::from_array(&model.joint_X_c[7 * j]);
    const Transform J = pj.inverse() * cj;
    const Vec3 w_rel = pj.q.conjugate() * (C.w - P.w);
    const Vec3 v_rel = pj.q.conjugate() * (C.point_velocity(cj.p) - P.point_velocity(cj.p));
    const Vec3 axis(model.joint_axis[3 * j], model.joint_axis[3 * j + 1], model.joint_axis[3 * j + 2]);
    Scalar* q = state.joint_q.data() + model.joint_q_start[j];
    Scalar* qd = state.joint_qd.data() + model.joint_qd_start[j];
    // a quaternion's sign as the state's before
    auto put_quat = [](Quat u, Scalar* x) {
      if (u.x() * x[0] + u.y() * x[1] + u.z() * x[2] + u.w() * x[3] < 0) u.coeffs() *= -1;
      x[0] = u.x(), x[1] = u.y(), x[2] = u.z(), x[3] = u.w();
    };
    switch (type) {
      case JointType::Revolute: {
        const Scalar angle = 2 * std::atan2(J.q.vec().dot(axis), J.q.w());
        q[0] += std::remainder(angle - q[0], 2 * kPi);
        qd[0] = axis.dot(w_rel);
        break;
      }
      case JointType::Prismatic:
        q[0] = axis.dot(J.p);
        qd[0] = axis.dot(v_rel);
        break;
      case JointType::Ball: {
        put_quat(J.q, q);
        const Vec3 w_child = J.q.conjugate() * w_rel;
        for (int k = 0; k < 3; ++k) qd[k] = w_child[k];
        break;
      }
      case JointType::Fixed: break;
      case JointType::Free:
      case JointType::Distance:
      case JointType::D6:
      case JointType::Cable:
        for (int k = 0; k < 3; ++k) q[k] = J.p[k], qd[k] = w_rel[k], qd[3 + k] = v_rel[k];
        put_quat(J.q, q + 3);
        break;
    }
  }
}

}  // namespace novaphy
