// The constraint rows of the step, each written once over the number type (kernels/number.h) and
// composed by both row builders (the blocks' lanes and the islands of articulations): their targets,
// warm starts and the impulses kept for the next step. A row drives J qd towards its target; sweeps
// (kernels/pgs, kernels/batch/pgs) clamp its impulse.
#pragma once

#include <algorithm>
#include <cmath>

#include "engine/model/model.h"
#include "engine/solver/parts/row_params.h"
#include "kernels/batch/pgs.h"
#include "kernels/number.h"
#include "kernels/pgs.h"

namespace novaphy {

// ---- joint limits: one row per side of a Revolute or Prismatic joint's range. With sign +1 for the
// lower limit and -1 for the upper, gap = sign (q - limit) >= 0 inside the range and the row keeps
// sign qd >= target

// the side's row is on this step: the joint would cross its limit within the step
template <typename V>
inline Mask<V> limit_row_on(const V& gap, const V& signed_qd, const V& dt) {
  return gap + dt * signed_qd < 0;
}

// close a gap in one step; push a penetration beyond the slop out at erp / dt
template <typename V>
inline V limit_row_target(const V& gap, const RowParams& p, const V& dt) {
  const V depth = -gap - static_cast<Element<V>>(p.linear_slop);
  const V zero{};
  return select<V>(gap >= 0, -gap / dt, static_cast<Element<V>>(p.erp) * select<V>(depth > 0, depth, zero) / dt);
}

// the share of its last step's impulses a world's rows but its contacts' (contact_warm_share) start from: all of
// them where its last sweeps converged (stopped at one that moved no row beyond pgs_tolerance), warmstarting_factor
// of them where they ran out (an error left by sweeps that ran out, carried whole from step to step, can build up),
// none without warm starting
template <typename V>
inline V warm_share(const Mask<V>& converged, const RowParams& p) {
  using E = Element<V>;
  if (!p.use_warmstarting) return V{};
  return select<V>(converged, splat<V>(E(1)), splat<V>(static_cast<E>(p.warmstarting_factor)));
}

// the share of their last impulses a contact's rows start from: all of them (none without warm starting), whether
// or not the sweeps converged. A contact's rows push and are bounded by friction, so carried whole they do not
// build up as an equality's can; a smaller share lets a stack creep, its friction restarting short of what holds it
template <typename V>
inline V contact_warm_share(const RowParams& p) {
  return splat<V>(static_cast<Element<V>>(p.use_warmstarting ? 1 : 0));
}

// the impulse a limit or friction-loss row keeps for the next step: 0 where it was off or is not finite
template <typename V>
inline V impulse_kept(const V& lambda, const Mask<V>& on) {
  return select<V>(both(on, finite(lambda)), lambda, V{});
}

// ---- equality constraints (model.h): bilateral rows (Bounded, no bound) that drive the constraint's error
// to zero, a share erp of it each step

template <typename V>
inline V equality_row_target(const V& error, const RowParams& p, const V& dt) {
  return -static_cast<Element<V>>(p.erp) * error / dt;
}

// a joint coupling's error q1 - q1_0 - poly(x) and its slope d poly / dx at x = q2 - q2_0 (e: its data)
inline Scalar joint_coupling_error(const Scalar* e, Scalar q1, Scalar q2, Scalar* slope) {
  const Scalar x = q2 - e[6];
  *slope = e[1] + x * (2 * e[2] + x * (3 * e[3] + x * 4 * e[4]));
  return q1 - e[5] - (e[0] + x * (e[1] + x * (e[2] + x * (e[3] + x * e[4]))));
}

// ---- dry friction (frictionloss): one row per dof, J = e_k, driving its velocity to zero with an impulse of at
// most frictionloss dt either way

template <typename V>
inline V friction_loss_bound(const V& frictionloss, const V& dt) {
  return frictionloss * dt;
}

// ---- contacts: a normal row and two friction rows along the tangents of contact_frame's (kernels/pgs.h); with condim
// 4 a torsional row (the relative angular velocity about the normal, |impulse| <= mu_torsion normal impulse),
// with 6 also two rolling rows (about the tangents, bounded together by mu_rolling normal impulse)

// a shape's numbers as a contact's friction and softness read them (the step reads a table of the distinct ones,
// made once: a model of replicated robots has few)
struct ContactMaterial {
  int condim = 3, priority = 0;
  Scalar mu = 0, torsion = 0, rolling = 0, restitution = 0, solmix = 0, solref[2] = {}, solimp[5] = {}, margin = 0,
         gap = 0;
};
inline ContactMaterial contact_material(const Model& model, int shape) {
  ContactMaterial m;
  m.condim = model.shape_condim[shape];
  m.priority = model.shape_priority[shape];
  m.mu = model.shape_mu[shape];
  m.torsion = model.shape_mu_torsion[shape];
  m.rolling = model.shape_mu_rolling[shape];
  m.restitution = model.shape_restitution[shape];
  m.solmix = model.shape_solmix[shape];
  for (int k = 0; k < 2; ++k) m.solref[k] = model.shape_solref[2 * shape + k];
  for (int k = 0; k < 5; ++k) m.solimp[k] = model.shape_solimp[5 * shape + k];
  m.margin = model.shape_margin[shape];
  m.gap = model.shape_gap[shape];
  return m;
}

// a contact's friction: its condim and coefficients (sliding, torsional, rolling), by the model's FrictionRule:
// GeometricMean the means of the shapes' and the larger condim; Mujoco the shape of higher priority decides,
// else the larger of each (condim 1: none)
struct ContactFriction {
  int condim = 3;
  Scalar mu = 0, torsion = 0, rolling = 0;
};
inline ContactFriction contact_friction_of(FrictionRule rule, const ContactMaterial& a, const ContactMaterial& b) {
  ContactFriction f;
  f.condim = std::max(a.condim, b.condim);
  if (rule == FrictionRule::GeometricMean) {
    f.mu = std::sqrt(a.mu * b.mu);
    f.torsion = std::sqrt(a.torsion * b.torsion);
    f.rolling = std::sqrt(a.rolling * b.rolling);
    return f;
  }
  const ContactMaterial* decides = a.priority > b.priority ? &a : b.priority > a.priority ? &b : nullptr;
  if (decides) f.condim = decides->condim;
  if (f.condim == 1) return f;
  auto pick = [&](Scalar ContactMaterial::*x) { return decides ? decides->*x : std::max(a.*x, b.*x); };
  f.mu = pick(&ContactMaterial::mu);
  f.torsion = pick(&ContactMaterial::torsion);
  f.rolling = pick(&ContactMaterial::rolling);
  return f;
}
inline ContactFriction contact_friction_of(const Model& model, int a, int b) {
  return contact_friction_of(model.friction_rule, contact_material(model, a), contact_material(model, b));
}
// the rows of a contact of that condim, or of at most that many friction dimensions: 3 (a normal row and two
// sliding rows; condim 1 has them with no friction), 4 (and a torsional row) or 6 (and two rolling rows)
inline int contact_row_count(int condim) { return condim >= 6 ? 6 : condim >= 4 ? 4 : 3; }

// the sliding friction coefficient alone
inline Scalar contact_friction(const Model& model, int a, int b) { return contact_friction_of(model, a, b).mu; }
inline Scalar contact_restitution(const ContactMaterial& a, const ContactMaterial& b) {
  return std::max(a.restitution, b.restitution);
}

// ---- soft contacts: MuJoCo's soft constraint (solref, solimp) over one step of the rows' sweeps. MuJoCo's rows
// satisfy J a + R f = aref with aref = -B v - K imp (pos - margin); times dt, with the impulse p = f dt, the
// step's J qd_out + R p = v + dt aref, v = J qd_in: a row of cfm R and target v + dt aref. A contact whose
// deciding solref is (0, 0) is rigid (contact_normal_target)

// a contact's softness, from its shapes' solref, solimp, solmix, priority, margin and gap (combined as MuJoCo
// combines geoms: contact_pair) and its penetration (contact_softness): the normal row's cfm R (0 while the
// contact is inactive, farther than margin - gap), the friction rows' (R / impratio), MuJoCo's B, and
// K imp (pos - margin)
struct ContactSoftness {
  bool soft = false;
  Scalar cfm_normal = 0, cfm_friction = 0;
  Scalar damping = 0;        // B
  Scalar spring = 0;         // K imp (pos - margin), pos = -depth: the acceleration it pushes out at (< 0)
  Scalar active_margin = 0;  // margin - gap: a contact nearer than this is active
};

// MuJoCo's impedance at a distance x past the active margin, from solimp (dmin, dmax, width, midpoint, power)
inline Scalar contact_impedance(const Scalar* solimp, Scalar x) {
  constexpr Scalar kMin = 1e-4, kMax = 0.9999;  // (MuJoCo's mjMINIMP, mjMAXIMP)
  const Scalar dmin = std::clamp(solimp[0], kMin, kMax), dmax = std::clamp(solimp[1], kMin, kMax);
  const Scalar width = solimp[2], mid = std::clamp(solimp[3], kMin, kMax), power = solimp[4];
  if (dmin == dmax || width <= 1e-15) return 0.5 * (dmin + dmax);
  const Scalar u = std::abs(x) / width;
  if (u >= 1) return dmax;
  // (power 2, MuJoCo's default, without std::pow: this runs per contact and step)
  const auto raise = [power](Scalar x, Scalar p) { return power == 2 ? (p == 2 ? x * x : x) : std::pow(x, p); };
  const Scalar y = power == 1 ? u
                   : u <= mid ? raise(u, power) / raise(mid, power - 1)
                              : 1 - raise(1 - u, power) / raise(1 - mid, power - 1);
  return dmin + y * (dmax - dmin);
}

// what a contact's friction, restitution and softness take from its two shapes for a step of dt: all but its
// depth and its bodies' weights (the step reads a table of the pairs of distinct materials, made once a dt)
struct ContactPair {
  ContactFriction friction;
  Scalar restitution = 0;
  bool soft = false;         // the deciding solref is not (0, 0)
  Scalar active_margin = 0;  // margin - gap: a contact nearer than this is active
  Scalar stiffness = 0;      // MuJoCo's K and B of the deciding solref and solimp at dt
  Scalar damping = 0;
  Scalar solimp[5] = {};
};
inline ContactPair contact_pair(FrictionRule rule, const ContactMaterial& a, const ContactMaterial& b, Scalar dt) {
  ContactPair pair;
  pair.friction = contact_friction_of(rule, a, b);
  pair.restitution = contact_restitution(a, b);
  // the shape of higher priority decides, else a mix weighted by solmix
  const int pa = a.priority, pb = b.priority;
  const Scalar wa = a.solmix, wb = b.solmix;
  const Scalar mix = pa != pb                   ? (pa > pb ? 1 : 0)
                     : wa < 1e-15 && wb < 1e-15 ? 0.5
                     : wa < 1e-15               ? 0
                     : wb < 1e-15               ? 1
                                                : wa / (wa + wb);
  const Scalar* ra = a.solref;
  const Scalar* rb = b.solref;
  Scalar solref[2];
  for (int k = 0; k < 2; ++k)
    solref[k] = (ra[0] > 0 && rb[0] > 0) || pa != pb ? mix * ra[k] + (1 - mix) * rb[k] : std::min(ra[k], rb[k]);
  for (int k = 0; k < 5; ++k) pair.solimp[k] = mix * a.solimp[k] + (1 - mix) * b.solimp[k];
  if (solref[0] == 0 && solref[1] == 0) return pair;
  pair.soft = true;
  pair.active_margin = std::max(a.margin, b.margin) - std::max(a.gap, b.gap);
  const Scalar dmax = std::clamp(pair.solimp[1], Scalar(1e-4), Scalar(0.9999));
  if (solref[0] > 0) {
    const Scalar tc = std::max(solref[0], 2 * dt);  // (MuJoCo's refsafe)
    pair.stiffness = 1 / std::max(Scalar(1e-15), dmax * dmax * tc * tc * solref[1] * solref[1]);
    pair.damping = 2 / std::max(Scalar(1e-15), dmax * tc);
  } else {
    pair.stiffness = -solref[0] / std::max(Scalar(1e-15), dmax * dmax);
    pair.damping = -solref[1] / std::max(Scalar(1e-15), dmax);
  }
  return pair;
}

// the shapes' contact numbers as a step reads them: the distinct materials, each shape's place among them and its
// body's invweight0 (0: a static body), and the table of the materials' pairs at the step's dt where the model has
// at most kPairTableMaterials of them (else each pair is made as it is read)
struct ShapeContacts {
  static constexpr int kPairTableMaterials = 32;
  const ContactMaterial* materials = nullptr;
  const int* shape_material = nullptr;
  const Scalar* shape_weight = nullptr;
  const ContactPair* pairs = nullptr;  // [material_count * material a + material b], or null
  int material_count = 0;
  FrictionRule rule = FrictionRule::Mujoco;
  Scalar dt = 0;
  // the table's entry, else the pair made into *made
  const ContactPair& pair(int shape_a, int shape_b, ContactPair* made) const {
    const int a = shape_material[shape_a], b = shape_material[shape_b];
    if (pairs) return pairs[material_count * a + b];
    return *made = contact_pair(rule, materials[a], materials[b], dt);
  }
};

// a contact's softness from its pair at penetration `depth`; weight_a, weight_b: the shapes' bodies'
// invweight0 (translational; 0 for a static body), impratio the model's
inline ContactSoftness contact_softness(const ContactPair& pair, Scalar weight_a, Scalar weight_b, Scalar impratio,
                                        Scalar depth) {
  ContactSoftness s;
  if (!pair.soft) return s;
  s.soft = true;
  s.active_margin = pair.active_margin;
  const Scalar x = -depth - s.active_margin;  // pos - margin: < 0 where active
  if (x >= 0) return s;
  const Scalar imp = contact_impedance(pair.solimp, x);
  s.cfm_normal = std::max(Scalar(1e-15), (1 - imp) / imp * (weight_a + weight_b));
  s.cfm_friction = s.cfm_normal / impratio;
  s.damping = pair.damping;
  s.spring = pair.stiffness * imp * x;
  return s;
}
// a shape's body's invweight0 (0: a static body), as contact_softness takes it
inline Scalar contact_weight(const Model& model, int shape) {
  const int body = model.shape_body[shape];
  return body < 0 ? Scalar(0) : model.body_invweight0[2 * body];
}

// the five numbers of a contact's softness as the blocks read them (ContactLists::softness): the normal row's cfm
// (-1: a rigid contact), the friction rows', B, K imp (pos - margin), the active margin
inline void contact_softness_row(const ContactSoftness& s, Scalar* out) {
  out[0] = s.soft ? s.cfm_normal : -1;
  out[1] = s.cfm_friction;
  out[2] = s.damping;
  out[3] = s.spring;
  out[4] = s.active_margin;
}

// the normal row's target: where active, v + dt aref; before, it may close the distance to the active margin
template <typename V>
inline V soft_normal_target(const V& depth, const V& v, const V& damping, const V& spring, const V& active_margin,
                            const V& dt) {
  const V reach = depth + active_margin;
  return select<V>(reach > 0, v - dt * (damping * v + spring), reach / dt);
}

// a torsional or rolling row's cfm (MuJoCo's elliptic cone): the sliding rows' R_1 times mu_1^2 / mu^2 (0 where
// its mu is 0: the row holds nothing)
template <typename V>
inline V soft_spin_cfm(const V& cfm_sliding, const V& mu_sliding, const V& mu) {
  return select<V>(mu > 0, cfm_sliding * (mu_sliding * mu_sliding) / select<V>(mu > 0, mu * mu, V{} + 1), V{});
}

// a friction row's target: its sliding damped by B over the step (MuJoCo's aref = -B v for friction)
template <typename V>
inline V soft_friction_target(const V& v, const V& damping, const V& dt) {
  return v - dt * damping * v;
}

// u [3]: the velocity of the point p [3] moved by the motion s [6] ([angular; linear], about the point p
// is measured from); a contact row's Jacobian entry for that motion along a direction d is d . u
template <typename V>
inline void point_velocity(const V* s, const V* p, V* u) {
  u[0] = s[3] + s[1] * p[2] - s[2] * p[1];
  u[1] = s[4] + s[2] * p[0] - s[0] * p[2];
  u[2] = s[5] + s[0] * p[1] - s[1] * p[0];
}

// d . (the velocity of the point p moved by the motion s), or with p null d . (its angular velocity): a
// row's Jacobian entry for the dof of motion s (the islands' rows, one double at a time)
inline Scalar motion_along(const Scalar* s, const Scalar* p, const Scalar* d) {
  Scalar u[3] = {s[0], s[1], s[2]};
  if (p) point_velocity(s, p, u);
  return d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
}

// the normal row's target: push the penetration beyond the slop out at erp / dt, let a gap close in one
// step; a contact that closes within this step faster than the restitution threshold bounces at
// -restitution times its approach speed (v_approach: J qd of the normal row at the step's start)
template <typename V>
inline V contact_normal_target(const V& depth, const V& v_approach, const V& restitution, const RowParams& p,
                               const V& dt) {
  using E = Element<V>;
  const E slop = static_cast<E>(p.linear_slop);
  const V zero{};
  const V target =
      select<V>(depth > slop, static_cast<E>(p.erp) * (depth - slop) / dt, select<V>(depth < 0, depth, zero) / dt);
  const V bounce = -restitution * v_approach;
  const Mask<V> approaching = v_approach < -static_cast<E>(p.restitution_threshold);
  const Mask<V> closing = both<Mask<V>>(approaching, depth - v_approach * dt >= 0);
  return select<V>(both<Mask<V>>(closing, bounce > target), bounce, target);
}

// the rows' starting impulses warm [6] (normal, t1, t2, then torsion about the normal and rolling about t1 and
// t2): the last step's impulse and spin impulse `previous` [6] (world vectors; 0 for a new contact) along this
// step's frame d [9], their share (contact_warm_share), never pulling along the normal
template <typename V>
inline void contact_warm_start(const V* previous, const V* d, const V& share, V* warm) {
  for (int e = 0; e < 6; ++e) {
    const V* P = previous + (e < 3 ? 0 : 3);
    const V* axis = d + 3 * (e % 3);
    warm[e] = share * (P[0] * axis[0] + P[1] * axis[1] + P[2] * axis[2]);
  }
  warm[0] = select<V>(warm[0] > 0, warm[0], V{});
}

// the impulse kept for the next step, a world vector P [3] on body b from the rows' impulses lambda [3]
// and the frame d [9] (the normal and tangent rows' impulse, or the torsional and rolling rows' angular
// impulse); 0 where it is not finite
template <typename V>
inline void contact_impulse_kept(const V* lambda, const V* d, V* P) {
  for (int m = 0; m < 3; ++m) P[m] = lambda[0] * d[m] + lambda[1] * d[3 + m] + lambda[2] * d[6 + m];
  const Mask<V> ok = both(both(finite(P[0]), finite(P[1])), finite(P[2]));
  for (int m = 0; m < 3; ++m) P[m] = select<V>(ok, P[m], V{});
}

}  // namespace novaphy
