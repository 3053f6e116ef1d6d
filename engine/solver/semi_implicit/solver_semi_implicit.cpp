#include "engine/solver/semi_implicit/solver_semi_implicit.h"

#include <algorithm>
#include <cmath>

#include "engine/solver/maximal/corrections.h"
#include "engine/solver/parts/contact_rows.h"
#include "engine/solver/parts/equality_rows.h"
#include "engine/solver/parts/limit_row.h"

namespace novaphy {

namespace {

constexpr int kKeptPerConstraint = 18;  // 3 per axis: locked or lower limit, upper limit, spring

Scalar row_velocity(const BodyRow& r, const std::vector<BodyMotion>& bodies) {
  Scalar v = 0;
  if (r.a >= 0) v += r.lin_a.dot(bodies[r.a].v) + r.ang_a.dot(bodies[r.a].w);
  if (r.b >= 0) v += r.lin_b.dot(bodies[r.b].v) + r.ang_b.dot(bodies[r.b].w);
  return v;
}

// J_x M^-1 J_y^T of two rows between the same bodies (a contact's)
Scalar row_coupling(const BodyRow& x, const BodyRow& y, const std::vector<BodyMotion>& bodies) {
  Scalar c = 0;
  if (x.a >= 0) c += bodies[x.a].inv_mass * x.lin_a.dot(y.lin_a) + x.ang_a.dot(y.turn_a);
  if (x.b >= 0) c += bodies[x.b].inv_mass * x.lin_b.dot(y.lin_b) + x.ang_b.dot(y.turn_b);
  return c;
}

void apply(const BodyRow& r, Scalar impulse, std::vector<BodyMotion>& bodies) {
  if (r.a >= 0) {
    BodyMotion& A = bodies[r.a];
    A.v += (A.inv_mass * impulse) * r.lin_a;
    A.w += impulse * r.turn_a;
  }
  if (r.b >= 0) {
    BodyMotion& B = bodies[r.b];
    B.v += (B.inv_mass * impulse) * r.lin_b;
    B.w += impulse * r.turn_b;
  }
}

// a row along `axis` of the point p riding on both bodies (a: minus), or of their relative rotation about it
BodyRow point_row(int a, int b, const BodyMotion* A, const BodyMotion* B, const Vec3& p, const Vec3& axis) {
  BodyRow r;
  r.a = a, r.b = b;
  if (A) r.lin_a = -axis, r.ang_a = -(p - A->x).cross(axis);
  if (B) r.lin_b = axis, r.ang_b = (p - B->x).cross(axis);
  return r;
}
BodyRow turn_row(int a, int b, const Vec3& axis) {
  BodyRow r;
  r.a = a, r.b = b;
  if (a >= 0) r.ang_a = -axis;
  if (b >= 0) r.ang_b = axis;
  return r;
}

// a row that is a spring of stiffness K and damping D along a coordinate x (its velocity the row's), with its pull
// and constant force, taken implicitly over dt: J v_next + cfm lambda = target
bool spring_row(const AxisSpring& s, Scalar x, Scalar dt, BodyRow& r) {
  const Scalar denominator = s.damping + dt * s.stiffness;
  if (!(denominator > 0)) return false;
  r.kind = RowKind::Bounded;
  r.bound = std::numeric_limits<Scalar>::infinity();
  r.cfm = 1 / (dt * denominator);
  r.target = (s.pull + s.force - s.stiffness * x) / denominator;
  return true;
}

}  // namespace

SolverSemiImplicit::SolverSemiImplicit(const Model& model, const SolverSemiImplicitSettings& settings_)
    : MaximalSolver(model, "SolverSemiImplicit"), settings(settings_) {
  settings.check();
  scratch_.resize(threads_);
  kept_.assign(kKeptPerConstraint * built_.constraints.size(), 0);
  converged_.assign(model.world_count, 1);
}

void SolverSemiImplicit::finish_row(BodyRow& r, Scratch& s, Scalar start) const {
  Scalar jmj = 0;
  if (r.a >= 0) {
    const BodyMotion& A = s.bodies[r.a];
    r.turn_a = A.inv_inertia * r.ang_a;
    jmj += A.inv_mass * r.lin_a.squaredNorm() + r.ang_a.dot(r.turn_a);
  }
  if (r.b >= 0) {
    const BodyMotion& B = s.bodies[r.b];
    r.turn_b = B.inv_inertia * r.ang_b;
    jmj += B.inv_mass * r.lin_b.squaredNorm() + r.ang_b.dot(r.turn_b);
  }
  r.inv_mass = row_inv_mass(jmj, static_cast<Scalar>(settings.cfm) + r.cfm);
  r.lambda = start;
}

void SolverSemiImplicit::contact_rows(int w, const StepInput& step, Scratch& s) const {
  const Contacts& contacts = step.contacts;
  const bool fresh = step.in.world_reset[w] != 0;
  int count = 0;
  const int* list = contacts_of(w, &count);
  s.contact_rows.resize(count + 1);
  for (int i = 0; i < count; ++i) {
    const int c = list[i];
    const int body_a = contacts.contact_body_a[c], body_b = contacts.contact_body_b[c];
    const int a = slot(body_a), b = slot(body_b);
    ContactInput<Scalar> in = ContactRows::read(contacts, c, shapes_, model_.impratio);
    if (fresh)
      for (int m = 0; m < 3; ++m) in.impulse[m] = in.spin[m] = 0;
    const int dims = ContactRows::count(std::min(static_cast<int>(in.condim), settings.max_condim));
    Scalar d[9];
    contact_frame(&contacts.contact_normal[3 * static_cast<size_t>(c)], d);
    const Vec3 p(contacts.contact_point[3 * c], contacts.contact_point[3 * c + 1], contacts.contact_point[3 * c + 2]);
    const BodyMotion* A = a >= 0 ? &s.bodies[a] : nullptr;
    const BodyMotion* B = b >= 0 ? &s.bodies[b] : nullptr;
    const int first = static_cast<int>(s.rows.size());
    s.contact_rows[i] = first;
    Scalar v[6] = {}, target[6] = {}, cfm[6] = {}, mu[6] = {}, warm[6] = {};
    for (int e = 0; e < dims; ++e) {
      const Scalar* dir = ContactRows::direction(d, e);
      const Vec3 axis(dir[0], dir[1], dir[2]);
      s.rows.push_back(ContactRows::turns(e) ? turn_row(a, b, axis) : point_row(a, b, A, B, p, axis));
      v[e] = row_velocity(s.rows.back(), s.bodies);
    }
    ContactRows::targets(in, v, dims, settings, step.dt, target, cfm, mu);
    ContactRows::warm(in, d, ContactRows::warm_share<Scalar>(settings), warm);
    for (int e = 0; e < dims; ++e) {
      BodyRow& r = s.rows[first + e];
      r.kind = ContactRows::kind(e, dims);
      r.normal = first;
      r.mu = mu[e];
      r.target = target[e];
      r.cfm = cfm[e];
    }
    for (int e = 0; e < dims; ++e) finish_row(s.rows[first + e], s, warm[e]);
  }
  s.contact_rows[count] = static_cast<int>(s.rows.size());
}

void SolverSemiImplicit::constraint_rows(int w, const StepInput& step, Scalar share, Scratch& s) {
  const Scalar dt = step.dt;
  const State& in = step.in;
  for (int ci = built_.world_start[w]; ci < built_.world_start[w + 1]; ++ci) {
    const MaximalConstraint& c = built_.constraints[ci];
    Scalar* kept = &kept_[kKeptPerConstraint * static_cast<size_t>(ci)];
    Scalar start[kKeptPerConstraint];
    for (int k = 0; k < kKeptPerConstraint; ++k) start[k] = share * kept[k], kept[k] = 0;
    const int a = slot(c.a), b = slot(c.b);
    const BodyMotion* A = a >= 0 ? &s.bodies[a] : nullptr;
    const BodyMotion* B = b >= 0 ? &s.bodies[b] : nullptr;
    const Transform frame_a = A ? A->frame(model_, c.a) * c.X_a : c.X_a;
    const Transform frame_b = B ? B->frame(model_, c.b) * c.X_b : c.X_b;
    Scalar coordinate[6];
    constraint_coordinates(c, frame_a, frame_b, coordinate);
    auto add = [&](BodyRow r, int slot) {
      r.kept = &kept[slot];
      finish_row(r, s, start[slot]);
      s.rows.push_back(r);
    };
    // a range's rows: each side whose limit the coordinate x would cross within the step (rigid: LimitRow), or has
    // crossed (compliant: a spring of stiffness 1 / compliance pushing back)
    auto limit_rows = [&](const BodyRow& along, Scalar x, Scalar lower, Scalar upper, Scalar compliance, int slot) {
      const Scalar x_dot = row_velocity(along, s.bodies);
      for (int side = 0; side < 2; ++side) {
        const Scalar limit = side == 0 ? lower : upper;
        const Scalar gap = LimitRow::gap(x, limit, side);
        const bool on =
            compliance > 0 ? std::isfinite(limit) && gap < 0 : LimitRow::on(limit, gap, x_dot, side, dt, false);
        if (!on) continue;
        BodyRow r = along;
        const Scalar sign = LimitRow::sign(side);
        r.lin_a *= sign, r.ang_a *= sign, r.lin_b *= sign, r.ang_b *= sign;
        r.kind = LimitRow::kKind;
        r.target = compliance > 0 ? -gap / dt : LimitRow::target(gap, settings, dt);
        r.cfm = compliance / (dt * dt);
        add(r, slot + side);
      }
    };
    if (c.distance) {
      const Vec3 gap = frame_b.p - frame_a.p;
      const Scalar length = gap.norm();
      if (length < 1e-9) continue;
      const Vec3 n = gap / length;
      BodyRow along;
      along.a = a, along.b = b;
      if (A) along.lin_a = -n, along.ang_a = -(frame_a.p - A->x).cross(n);
      if (B) along.lin_b = n, along.ang_b = (frame_b.p - B->x).cross(n);
      limit_rows(along, length, c.lower[3], c.upper[3], c.compliance[0], 9);
      continue;
    }
    for (int k = 0; k < 6; ++k) {
      const Vec3 axis = frame_a.q * Vec3::Unit(k % 3);
      const BodyRow along = k < 3 ? turn_row(a, b, axis) : point_row(a, b, A, B, frame_b.p, axis);
      const Scalar x = axis_coordinate(c, k, in, coordinate[k]);
      const Scalar compliance = c.compliance[k < 3 ? 1 : 0];
      switch (c.mode[k]) {
        case AxisMode::Free: break;
        case AxisMode::Locked: {
          BodyRow r = along;
          r.kind = EqualityRow::kKind;
          r.bound = EqualityRow::bound();
          const Scalar error = x - c.lower[k];
          r.target = compliance > 0 ? -error / dt : EqualityRow::target(error, settings, dt);
          r.cfm = compliance / (dt * dt);
          add(r, 3 * k);
          break;
        }
        case AxisMode::Limited: limit_rows(along, x, c.lower[k], c.upper[k], compliance, 3 * k); break;
      }
      if (c.mode[k] == AxisMode::Locked) continue;
      const AxisSpring spring = axis_spring(c, k, in, step.control);
      if (!spring.any()) continue;
      BodyRow r = along;
      if (spring_row(spring, x, dt, r)) {
        add(r, 3 * k + 2);
      } else {  // a constant force alone
        finish_row(r, s, 0);
        apply(r, dt * (spring.pull + spring.force), s.bodies);
      }
    }
  }
}

bool SolverSemiImplicit::sweep(Scratch& s) const {
  std::vector<BodyRow>& rows = s.rows;
  const Scalar smoothing = settings.friction_smoothing;
  // a row's residual J v - target + cfm lambda, and its impulse stepped to bring that to 0
  auto residual_of = [&](const BodyRow& x) {
    return row_velocity(x, s.bodies) - x.target + (static_cast<Scalar>(settings.cfm) + x.cfm) * x.lambda;
  };
  auto raw = [&](const BodyRow& x) { return x.lambda - x.inv_mass * residual_of(x); };
  for (int it = 0; it < settings.num_iterations; ++it) {
    Scalar largest = 0;  // the largest change of a row's velocity this sweep
    for (size_t i = 0; i < rows.size(); ++i) {
      BodyRow& r = rows[i];
      if (r.inv_mass == 0) continue;
      const int at = static_cast<int>(i);
      if (const int g = cone_after(
              at, static_cast<int>(rows.size()), at, [&](int k) { return rows[k].kind; },
              [&](int k) { return rows[k].normal; })) {
        // a contact's normal and friction cone rows: one block update (kernels/pgs.h)
        const int n = 1 + g;
        ConeBlock<Scalar> block;
        Scalar* A = block.A;
        Scalar lambda[kMaxContact], residual[kMaxContact], mu[kMaxContact], p[kMaxContact];
        for (int k = 0; k < n; ++k) {
          const BodyRow& x = rows[i + k];
          const bool massive = x.inv_mass > 0;
          lambda[k] = x.lambda;
          mu[k] = x.mu;
          residual[k] = massive ? residual_of(x) : 0;
          A[k * kMaxContact + k] = massive ? 1 / x.inv_mass : 1;
          for (int j = 0; j < k; ++j)
            A[k * kMaxContact + j] = A[j * kMaxContact + k] = row_coupling(x, rows[i + j], s.bodies);
        }
        block.prepare(n - 1);
        solve_contact_cone(block, lambda, residual, mu + 1, smoothing, p);
        for (int k = 0; k < n; ++k) {
          BodyRow& x = rows[i + k];
          const Scalar change = p[k] - x.lambda;
          if (!std::isfinite(change)) continue;
          apply(x, change, s.bodies);
          largest = std::max(largest, std::abs(change) / std::max(x.inv_mass, 1e-300));
          x.lambda = p[k];
        }
        i += n - 1;
        continue;
      }
      if (r.kind == RowKind::FrictionCone) continue;  // (updated with its normal row only)
      if (r.kind == RowKind::FrictionPair) {
        BodyRow& r2 = rows[i + 1];
        const Scalar l1 = raw(r), l2 = raw(r2);
        Scalar p1, p2;
        project_friction_pair(l1, l2, r.mu * rows[r.normal].lambda, smoothing, &p1, &p2);
        const Scalar d1 = p1 - r.lambda, d2 = p2 - r2.lambda;
        if (std::isfinite(d1) && std::isfinite(d2)) {
          apply(r, d1, s.bodies), apply(r2, d2, s.bodies);
          r.lambda = p1, r2.lambda = p2;
          largest = std::max({largest, std::abs(d1) / r.inv_mass, std::abs(d2) / std::max(r2.inv_mass, 1e-300)});
        }
        ++i;
        continue;
      }
      const Scalar stepped = raw(r);
      Scalar next = stepped;
      switch (r.kind) {
        case RowKind::Unilateral: next = project_unilateral(stepped); break;
        case RowKind::Bounded: next = project_bounded(stepped, r.bound); break;
        case RowKind::FrictionOne: next = project_bounded(stepped, r.mu * rows[r.normal].lambda); break;
        case RowKind::FrictionPair:
        case RowKind::FrictionCone: break;
      }
      const Scalar change = next - r.lambda;
      if (!std::isfinite(change)) continue;
      apply(r, change, s.bodies);
      r.lambda = next;
      largest = std::max(largest, std::abs(change) / r.inv_mass);
    }
    if (largest <= settings.pgs_tolerance) return true;
  }
  return rows.empty();
}

void SolverSemiImplicit::step_world(int w, const StepInput& step, int thread) {
  Scratch& s = scratch_[thread];
  const int first = built_.body_start[w], count = built_.body_start[w + 1] - first;
  s.bodies.resize(count);
  s.rows.clear();
  for (int i = 0; i < count; ++i) s.bodies[i] = start_motion(step.in, built_.world_bodies[first + i]);
  const bool fresh = step.in.world_reset[w] != 0;
  const Scalar share = fresh || !settings.use_warmstarting ? 0
                       : converged_[w]                     ? 1
                                                           : static_cast<Scalar>(settings.warmstarting_factor);
  contact_rows(w, step, s);
  forces(w, step.in, step.control, step.dt, s.bodies);
  constraint_rows(w, step, share, s);
  // the rows' starting impulses, once every row read the velocities it starts from (a contact's restitution, a
  // limit's crossing): applied as each row was made, one contact's warm start changed the next one's approach
  for (const BodyRow& r : s.rows)
    if (r.lambda != 0) apply(r, r.lambda, s.bodies);
  converged_[w] = sweep(s);
  for (BodyRow& r : s.rows)
    if (r.kept) *r.kept = std::isfinite(r.lambda) ? r.lambda : 0;
  // the contacts' impulses kept for the next step
  int contacts = 0;
  const int* list = contacts_of(w, &contacts);
  for (int i = 0; i < contacts; ++i) {
    const int c = list[i], row = s.contact_rows[i], dims = s.contact_rows[i + 1] - row;
    Scalar d[9], lambda[6] = {}, P[6];
    contact_frame(&step.contacts.contact_normal[3 * static_cast<size_t>(c)], d);
    for (int e = 0; e < dims; ++e) lambda[e] = s.rows[row + e].lambda;
    ContactRows::keep(lambda, dims, d, P);
    for (int m = 0; m < 3; ++m)
      step.contacts.contact_impulse[3 * c + m] = P[m], step.contacts.contact_spin_impulse[3 * c + m] = P[3 + m];
  }
  // semi-implicit integration, then the rigid joints' drift taken out of the positions
  const Scalar dt = step.dt, damping = std::max(Scalar(0), 1 - settings.angular_damping * dt);
  for (BodyMotion& m : s.bodies) {
    if (m.inv_mass == 0) continue;
    m.w *= damping;
    m.x += dt * m.v;
    m.q = turned(m.q, dt * m.w);
    m.orient();
  }
  hold_joints(w, s);
  for (int i = 0; i < count; ++i)
    if (s.bodies[i].inv_mass > 0) next_[built_.world_bodies[first + i]] = s.bodies[i];
}

void SolverSemiImplicit::hold_joints(int w, Scratch& s) const {
  Scalar lambda[2];
  for (int pass = 0; pass < settings.position_iterations; ++pass)
    for (int ci = built_.world_start[w]; ci < built_.world_start[w + 1]; ++ci) {
      const MaximalConstraint& c = built_.constraints[ci];
      if (c.compliance[0] > 0 || c.compliance[1] > 0) continue;  // (a compliant one is a spring: its drift is its own)
      lambda[0] = lambda[1] = 0;
      hold_constraint(model_, c, slot(c.a), slot(c.b), HoldSettings{}, lambda, s.bodies);
    }
}

}  // namespace novaphy
