#include "engine/solver/xpbd/solver_xpbd.h"

#include <algorithm>
#include <cmath>

#include "engine/solver/maximal/corrections.h"
#include "engine/solver/parts/contact_rows.h"

namespace novaphy {

namespace {

constexpr Scalar kPi = 3.14159265358979323846;
constexpr Scalar kTiny = 1e-12;
constexpr int kMultipliers = 8;  // per constraint: its rotation, its offset (or distance), each axis's stiffness

// an angular coordinate's change wrapped to (-pi, pi]
Scalar wrapped(Scalar x) { return std::remainder(x, 2 * kPi); }

}  // namespace

SolverXPBD::SolverXPBD(const Model& model, const SolverXPBDSettings& settings_)
    : MaximalSolver(model, "SolverXPBD"), settings(settings_) {
  settings.check();
  scratch_.resize(threads_);
}

void SolverXPBD::predict(int w, const StepInput& step, Scalar h, Scratch& s) const {
  forces(w, step.in, step.control, h, s.bodies);
  for (size_t i = 0; i < s.bodies.size(); ++i) {
    BodyMotion& m = s.bodies[i];
    if (m.inv_mass == 0) continue;
    m.x += h * m.v;
    m.q = turned_slightly(m.q, h * m.w);
    m.orient();
  }
}

void SolverXPBD::solve_constraint(const MaximalConstraint& c, const AxisSpring* springs, const State& in, Scalar h,
                                  Scalar* lambda, Scratch& s) const {
  const int a = slot(c.a), b = slot(c.b);
  const Scalar h2 = h * h;
  HoldSettings hold;
  hold.alpha_linear = (c.compliance[0] + settings.joint_linear_compliance) / h2;
  hold.alpha_angular = (c.compliance[1] + settings.joint_angular_compliance) / h2;
  hold.relax_linear = settings.joint_linear_relaxation;
  hold.relax_angular = settings.joint_angular_relaxation;
  hold_constraint(model_, c, a, b, hold, lambda, s.bodies);
  Transform frame_a, frame_b;
  Scalar coordinate[6];
  // the stiffnesses along free and limited axes (drives, springs, servos) as constraints of compliance 1 / K towards
  // their rest
  for (int k = 0; k < 6; ++k) {
    const AxisSpring& spring = springs[k];
    if (c.mode[k] == AxisMode::Locked || !(spring.stiffness > 0)) continue;
    frame_a = a >= 0 ? s.bodies[a].frame(model_, c.a) * c.X_a : c.X_a;
    frame_b = b >= 0 ? s.bodies[b].frame(model_, c.b) * c.X_b : c.X_b;
    constraint_coordinates(c, frame_a, frame_b, coordinate);
    const Scalar x = wound(c, k, in, coordinate[k]);
    const Vec3 axis = frame_a.q * Vec3::Unit(k % 3);
    const Scalar alpha = 1 / (spring.stiffness * h2);
    if (k < 3)
      turn(s.bodies, a, b, axis, x - spring.rest(), alpha, &lambda[2 + k], settings.joint_angular_relaxation);
    else
      push(s.bodies, a, b, frame_b.p, frame_b.p, axis, x - spring.rest(), alpha, &lambda[2 + k],
           settings.joint_linear_relaxation);
  }
}

void SolverXPBD::solve_contact(XContact& c, Scratch& s) const {
  const BodyMotion* A = c.a >= 0 ? &s.bodies[c.a] : nullptr;
  const BodyMotion* B = c.b >= 0 ? &s.bodies[c.b] : nullptr;
  auto at = [](const BodyMotion* m, const Vec3& r) { return m ? Vec3(m->x + m->q * r) : r; };
  const Vec3 pa = at(A, c.r_a), pb = at(B, c.r_b);
  const Scalar depth = (pa - pb).dot(c.n) - c.allowed;
  if (depth <= 0) return;
  Scalar unused = 0;
  c.lambda_n +=
      correct_position(s.bodies, c.a, c.b, pa, pb, depth * c.n, 0, &unused, settings.rigid_contact_relaxation);
}

void SolverXPBD::hold_contact(XContact& c, Scratch& s) const {
  if (c.lambda_n <= 0) return;
  const BodyMotion* A = c.a >= 0 ? &s.bodies[c.a] : nullptr;
  const BodyMotion* B = c.b >= 0 ? &s.bodies[c.b] : nullptr;
  const BodyMotion* A0 = c.a >= 0 ? &s.before[c.a] : nullptr;
  const BodyMotion* B0 = c.b >= 0 ? &s.before[c.b] : nullptr;
  auto at = [](const BodyMotion* m, const Vec3& r) { return m ? Vec3(m->x + m->q * r) : r; };
  Scalar unused = 0;
  // static friction: the points' relative tangential motion over the substep undone while the friction holds
  const Vec3 pa_now = at(A, c.r_a), pb_now = at(B, c.r_b);
  const Vec3 moved = (pa_now - at(A0, c.r_a)) - (pb_now - at(B0, c.r_b));
  const Vec3 slide = moved - moved.dot(c.n) * c.n;
  const Scalar length = slide.norm();
  if (length < kTiny) return;
  const Vec3 t = slide / length;
  const Scalar w = inverse_mass(s.bodies, c.a, pa_now, t) + inverse_mass(s.bodies, c.b, pb_now, t);
  if (w < kTiny || c.lambda_t + length / w >= c.mu * c.lambda_n) return;
  c.lambda_t +=
      correct_position(s.bodies, c.a, c.b, pa_now, pb_now, slide, 0, &unused, settings.rigid_contact_relaxation);
}

void SolverXPBD::velocity_pass(int w, Scalar h, Scratch& s) const {
  const Vec3 g(model_.world_gravity[3 * w], model_.world_gravity[3 * w + 1], model_.world_gravity[3 * w + 2]);
  // a contact's points now and their relative velocity (b's minus a's)
  auto relative = [&](const XContact& c, Vec3& pa, Vec3& pb) {
    const BodyMotion* A = c.a >= 0 ? &s.bodies[c.a] : nullptr;
    const BodyMotion* B = c.b >= 0 ? &s.bodies[c.b] : nullptr;
    pa = A ? Vec3(A->x + A->q * c.r_a) : c.r_a;
    pb = B ? Vec3(B->x + B->q * c.r_b) : c.r_b;
    return Vec3((B ? B->point_velocity(pb) : Vec3::Zero()) - (A ? A->point_velocity(pa) : Vec3::Zero()));
  };
  // the normal velocities of the contacts this substep pushed apart, Gauss-Seidel `iterations` times over them (one
  // pass leaves a resting box spinning from its corners' turns): what the restitution leaves of the approach, none
  // where it was slow
  for (int it = 0; it < settings.iterations; ++it)
    for (const XContact& c : s.contacts) {
      if (c.lambda_n <= 0) continue;
      Vec3 pa, pb;
      const Scalar vn = c.n.dot(relative(c, pa, pb));
      const Scalar e = settings.enable_restitution && std::abs(c.approach) > 2 * g.norm() * h ? c.restitution : 0;
      const Scalar inv = inverse_mass(s.bodies, c.a, pa, c.n) + inverse_mass(s.bodies, c.b, pb, c.n);
      if (inv > kTiny)
        apply_impulse(s.bodies, c.a, c.b, pa, pb, ((std::max(-e * c.approach, Scalar(0)) - vn) / inv) * c.n);
    }
  // dynamic friction: an impulse against the sliding of at most mu times the normal impulse (lambda_n / h)
  for (const XContact& c : s.contacts) {
    if (c.lambda_n <= 0) continue;
    Vec3 pa, pb;
    const Vec3 v = relative(c, pa, pb);
    const Vec3 slide = v - c.n.dot(v) * c.n;
    const Scalar speed = slide.norm();
    if (speed < kTiny) continue;
    const Vec3 t = slide / speed;
    const Scalar inv = inverse_mass(s.bodies, c.a, pa, t) + inverse_mass(s.bodies, c.b, pb, t);
    if (inv > kTiny) apply_impulse(s.bodies, c.a, c.b, pa, pb, -std::min(c.mu * c.lambda_n / h, speed / inv) * t);
  }
  // each axis's damper and constant force, implicitly over h, at the substep's end (its stiffness was a constraint)
  for (int ci = built_.world_start[w]; ci < built_.world_start[w + 1]; ++ci) {
    const MaximalConstraint& c = built_.constraints[ci];
    const AxisSpring* springs = &s.springs[6 * static_cast<size_t>(ci - built_.world_start[w])];
    const int a = slot(c.a), b = slot(c.b);
    const Transform frame_a = a >= 0 ? s.bodies[a].frame(model_, c.a) * c.X_a : c.X_a;
    const Transform frame_b = b >= 0 ? s.bodies[b].frame(model_, c.b) * c.X_b : c.X_b;
    for (int k = 0; k < 6; ++k) {
      const AxisSpring& spring = springs[k];
      if (c.mode[k] == AxisMode::Locked || (spring.damping == 0 && spring.force == 0)) continue;
      const Vec3 axis = frame_a.q * Vec3::Unit(k % 3);
      Scalar x_dot, inv;
      const Vec3 p = frame_b.p;
      if (k < 3) {
        x_dot = axis.dot((b >= 0 ? s.bodies[b].w : Vec3::Zero()) - (a >= 0 ? s.bodies[a].w : Vec3::Zero()));
        inv = (a >= 0 ? axis.dot(s.bodies[a].inv_inertia * axis) : 0) +
              (b >= 0 ? axis.dot(s.bodies[b].inv_inertia * axis) : 0);
      } else {
        x_dot = axis.dot((b >= 0 ? s.bodies[b].point_velocity(p) : Vec3::Zero()) -
                         (a >= 0 ? s.bodies[a].point_velocity(p) : Vec3::Zero()));
        inv = inverse_mass(s.bodies, a, p, axis) + inverse_mass(s.bodies, b, p, axis);
      }
      // (D v_next = force - lambda / h: a damper of the force's own speed)
      const Scalar impulse = spring.damping > 0
                                 ? (spring.force / spring.damping - x_dot) / (inv + 1 / (h * spring.damping))
                                 : h * spring.force;
      if (k < 3) {
        if (b >= 0) s.bodies[b].w += s.bodies[b].inv_inertia * (impulse * axis);
        if (a >= 0) s.bodies[a].w -= s.bodies[a].inv_inertia * (impulse * axis);
      } else {
        apply_impulse(s.bodies, a, b, p, p, impulse * axis);
      }
    }
  }
}

Scalar SolverXPBD::wound(const MaximalConstraint& c, int k, const State& in, Scalar coordinate) const {
  const Scalar joint_x = axis_coordinate(c, k, in, coordinate);
  if (joint_x == coordinate) return coordinate;
  return joint_x + (k < 3 ? wrapped(coordinate - joint_x) : coordinate - joint_x);
}

void SolverXPBD::step_world(int w, const StepInput& step, int thread) {
  Scratch& s = scratch_[thread];
  const int first = built_.body_start[w], count = built_.body_start[w + 1] - first;
  s.bodies.resize(count);
  s.body.resize(count);
  for (int i = 0; i < count; ++i) {
    s.body[i] = built_.world_bodies[first + i];
    s.bodies[i] = start_motion(step.in, s.body[i]);
  }
  // the contacts: their points on each body at the step's start, where the contact found them
  int contacts = 0;
  const int* list = contacts_of(w, &contacts);
  s.contacts.resize(contacts);
  for (int i = 0; i < contacts; ++i) {
    const int c = list[i];
    const Contacts& in = step.contacts;
    XContact& x = s.contacts[i];
    x.a = slot(in.contact_body_a[c]);
    x.b = slot(in.contact_body_b[c]);
    x.n = Vec3(in.contact_normal[3 * c], in.contact_normal[3 * c + 1], in.contact_normal[3 * c + 2]);
    const Vec3 point(in.contact_point[3 * c], in.contact_point[3 * c + 1], in.contact_point[3 * c + 2]);
    const Scalar depth = in.contact_depth[c];
    x.depth = depth;
    const Vec3 pa = point + 0.5 * depth * x.n, pb = point - 0.5 * depth * x.n;
    x.r_a = x.a >= 0 ? Vec3(s.bodies[x.a].q.conjugate() * (pa - s.bodies[x.a].x)) : pa;
    x.r_b = x.b >= 0 ? Vec3(s.bodies[x.b].q.conjugate() * (pb - s.bodies[x.b].x)) : pb;
    const ContactInput<Scalar> read = ContactRows::read(in, c, shapes_, model_.impratio);
    x.mu = read.mu;
    x.restitution = read.restitution;
  }
  const int constraints = built_.world_start[w + 1] - built_.world_start[w];
  s.lambda.resize(kMultipliers * static_cast<size_t>(constraints));
  s.springs.resize(6 * static_cast<size_t>(constraints));
  for (int ci = 0; ci < constraints; ++ci)
    for (int k = 0; k < 6; ++k)
      s.springs[6 * ci + k] = axis_spring(built_.constraints[built_.world_start[w] + ci], k, step.in, step.control);
  const Scalar h = step.dt / settings.substeps;
  for (int sub = 0; sub < settings.substeps; ++sub) {
    s.before = s.bodies;
    for (XContact& c : s.contacts) {
      c.lambda_n = c.lambda_t = 0;
      c.allowed = std::max(Scalar(0), c.depth - settings.max_depenetration_velocity * (sub + 1) * h);
      const BodyMotion* A = c.a >= 0 ? &s.bodies[c.a] : nullptr;
      const BodyMotion* B = c.b >= 0 ? &s.bodies[c.b] : nullptr;
      const Vec3 pa = A ? Vec3(A->x + A->q * c.r_a) : c.r_a, pb = B ? Vec3(B->x + B->q * c.r_b) : c.r_b;
      c.approach = c.n.dot((B ? B->point_velocity(pb) : Vec3::Zero()) - (A ? A->point_velocity(pa) : Vec3::Zero()));
    }
    std::fill(s.lambda.begin(), s.lambda.end(), 0);
    predict(w, step, h, s);
    for (int it = 0; it < settings.iterations; ++it) {
      for (int ci = 0; ci < constraints; ++ci)
        solve_constraint(built_.constraints[built_.world_start[w] + ci], &s.springs[6 * ci], step.in, h,
                         &s.lambda[kMultipliers * ci], s);
      for (XContact& c : s.contacts) solve_contact(c, s);
      for (XContact& c : s.contacts) hold_contact(c, s);
    }
    // the velocities the positions moved at
    for (int i = 0; i < count; ++i) {
      BodyMotion& m = s.bodies[i];
      if (m.inv_mass == 0) continue;
      const BodyMotion& m0 = s.before[i];
      m.v = (m.x - m0.x) / h;
      Quat turn = m.q * m0.q.conjugate();
      if (turn.w() < 0) turn.coeffs() *= -1;
      m.w = (2 / h) * turn.vec();
    }
    velocity_pass(w, h, s);
    const Scalar damping = std::max(Scalar(0), 1 - settings.angular_damping * h);
    for (BodyMotion& m : s.bodies) m.w *= damping;
  }
  for (int i = 0; i < count; ++i)
    if (s.bodies[i].inv_mass > 0) next_[s.body[i]] = s.bodies[i];
  // the contacts' impulses: the normal and friction corrections over the step's time, on b
  for (int i = 0; i < contacts; ++i) {
    const int c = list[i];
    const XContact& x = s.contacts[i];
    for (int m = 0; m < 3; ++m)
      step.contacts.contact_impulse[3 * c + m] = x.lambda_n / h * x.n[m],
                                            step.contacts.contact_spin_impulse[3 * c + m] = 0;
  }
}

}  // namespace novaphy
