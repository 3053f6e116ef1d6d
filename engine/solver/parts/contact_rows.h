// A contact's rows, over the number type (kernels/number.h: one contact, or one a lane of a SIMD block): a normal row
// and two sliding rows along the tangents of contact_frame's (kernels/pgs.h); with condim 4 a torsional row (the
// relative angular velocity about the normal), with 6 also two rolling rows (about the tangents); with either, all of
// its friction rows bounded together in MuJoCo's elliptic cone (kind). Rigid or soft (contact_softness.h) by its
// shapes' solref. Both row builders (the blocks' lanes, the islands) lay out the Jacobians and solve M^-1 J^T; what
// the rows are is here.
#pragma once

#include "engine/collision/pipeline.h"
#include "engine/solver/parts/contact_material.h"
#include "engine/solver/parts/contact_softness.h"
#include "engine/solver/settings.h"
#include "kernels/pgs.h"

namespace novaphy {

// what a contact's rows read of it beside its geometry (normal, point, bodies)
template <typename V>
struct ContactInput {
  V depth{}, mu{}, restitution{};   // mu: sliding friction
  V impulse[3] = {}, spin[3] = {};  // the last step's impulse and spin impulse (world vectors; 0 for a new contact)
  ContactSoftness<V> softness;
  V condim{}, torsion{}, rolling{};  // friction about the normal and about the tangents
};

struct ContactRows {
  // row e's kind in a contact of `dims` rows: the normal (e 0) Unilateral; with three rows the sliding pair a
  // FrictionPair (MuJoCo's elliptic cone of condim 3: a disk); with four or six, every friction row (sliding,
  // torsional, rolling) of one FrictionCone, bounded together as MuJoCo's elliptic cone bounds them
  static RowKind kind(int e, int dims) {
    return e == 0 ? RowKind::Unilateral : dims > 3 ? RowKind::FrictionCone : RowKind::FrictionPair;
  }
  // the condim from which a contact has row e: the normal and sliding rows always (condim 1 has them with no
  // friction), the torsional row from 4, the rolling rows from 6
  static int first_condim(int e) { return e < 3 ? 0 : e == 3 ? 4 : 6; }
  // where a contact of that condim has row e
  template <typename V>
  static Mask<V> has(int e, const V& condim) {
    return condim >= static_cast<Element<V>>(first_condim(e));
  }
  // the rows of a contact of that condim, or of at most that many friction dimensions: 3, 4 or 6
  static int count(int condim) {
    int rows = 3;
    while (rows < 6 && condim >= first_condim(rows)) ++rows;
    return rows;
  }
  // whether row e is of the relative angular velocity (torsion, rolling) rather than of the contact point's velocity
  static bool turns(int e) { return e >= 3; }
  // row e's direction in the contact's frame d [9]: the normal or a tangent, or the axis it turns about
  template <typename V>
  static const V* direction(const V* d, int e) {
    return d + 3 * (e < 3 ? e : e == 3 ? 0 : e - 3);
  }

  // contact c's input: its depth, its pair's friction and restitution (ShapeContacts), its softness, the impulses
  // it kept. Inlined into the row builders' loops over contacts: called, it took 3 % of a step (house.md)
  [[gnu::always_inline]] static ContactInput<Scalar> read(const Contacts& contacts, int c, const ShapeContacts& shapes,
                                                          Scalar impratio) {
    ContactInput<Scalar> in;
    ContactPair made;  // (a pair past the table: ShapeContacts::pair)
    const int sa = contacts.contact_shape_a[c], sb = contacts.contact_shape_b[c];
    const ContactPair& pair = shapes.pair(sa, sb, &made);
    in.depth = contacts.contact_depth[c];
    in.mu = pair.friction.mu;
    in.restitution = pair.restitution;
    if (const Scalar* P = contacts.previous(c))
      for (int m = 0; m < 3; ++m) in.impulse[m] = P[m], in.spin[m] = P[3 + m];
    in.softness = contact_softness(pair, shapes.shape_weight[sa], shapes.shape_weight[sb], impratio, in.depth);
    in.condim = pair.friction.condim;
    in.torsion = pair.friction.torsion;
    in.rolling = pair.friction.rolling;
    return in;
  }

  // lane l of a block's input from one contact's
  template <typename V>
  static void set_lane(ContactInput<V>& lanes, int l, const ContactInput<Scalar>& one) {
    auto put = [l](V& x, Scalar value) { x[l] = static_cast<Element<V>>(value); };
    put(lanes.depth, one.depth);
    put(lanes.mu, one.mu);
    put(lanes.restitution, one.restitution);
    for (int m = 0; m < 3; ++m) put(lanes.impulse[m], one.impulse[m]), put(lanes.spin[m], one.spin[m]);
    const ContactSoftness<Scalar>& s = one.softness;
    lanes.softness.soft[l] = s.soft ? -1 : 0;
    put(lanes.softness.cfm_normal, s.cfm_normal);
    put(lanes.softness.cfm_friction, s.cfm_friction);
    put(lanes.softness.damping, s.damping);
    put(lanes.softness.spring, s.spring);
    put(lanes.softness.active_margin, s.active_margin);
    put(lanes.condim, one.condim);
    put(lanes.torsion, one.torsion);
    put(lanes.rolling, one.rolling);
  }

  // the share of their last impulses a contact's rows start from: all of them (none without warm starting),
  // whether or not the sweeps converged. A contact's rows push and are bounded by friction, so carried whole they do
  // not build up as an equality's can; a smaller share lets a stack creep, its friction restarting short of what
  // holds it
  template <typename V, typename Settings>
  static V warm_share(const Settings& p) {
    return splat<V>(static_cast<Element<V>>(p.use_warmstarting ? 1 : 0));
  }

  // the rows' starting impulses warm [6] (normal, t1, t2, then torsion about the normal and rolling about t1 and
  // t2): the impulse and spin impulse it kept (in.impulse, in.spin) along this step's frame d [9], their share, never
  // pulling along the normal
  template <typename V>
  static void warm(const ContactInput<V>& in, const V* d, const V& share, V* warm) {
    for (int e = 0; e < 6; ++e) {
      const V* P = e < 3 ? in.impulse : in.spin;
      const V* axis = d + 3 * (e % 3);
      warm[e] = share * (P[0] * axis[0] + P[1] * axis[1] + P[2] * axis[2]);
    }
    warm[0] = select<V>(warm[0] > 0, warm[0], V{});
  }

  // a rigid normal row's target: push the penetration beyond the slop out at erp / dt, let a gap close in one
  // step; a contact that closes within this step faster than the restitution threshold bounces at
  // -restitution times its approach speed (v_approach: J qd of the normal row at the step's start)
  template <typename V, typename Settings>
  static V rigid_normal_target(const V& depth, const V& v_approach, const V& restitution, const Settings& p,
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

  // rows e < dims: their targets, cfm (a soft contact's; 0 for a rigid one) and friction coefficients mu (0 for the
  // normal), from their velocities v at the step's start
  template <typename V, typename Settings>
  static void targets(const ContactInput<V>& in, const V* v, int dims, const Settings& p, const V& dt, V* target,
                      V* cfm, V* mu) {
    const ContactSoftness<V>& s = in.softness;
    target[0] = select<V>(s.soft, soft_normal_target(in.depth, v[0], s.damping, s.spring, s.active_margin, dt),
                          rigid_normal_target(in.depth, v[0], in.restitution, p, dt));
    cfm[0] = select<V>(s.soft, s.cfm_normal, V{});
    mu[0] = V{};
    for (int e = 1; e < dims; ++e) {
      mu[e] = e < 3 ? in.mu : e == 3 ? in.torsion : in.rolling;
      target[e] = select<V>(s.soft, soft_friction_target(v[e], s.damping, dt), V{});
      cfm[e] = select<V>(s.soft, e < 3 ? s.cfm_friction : soft_spin_cfm(s.cfm_friction, in.mu, mu[e]), V{});
    }
  }

  // the impulses it keeps for the next step from its rows' lambda [dims]: world vectors P [6] on body b, the normal
  // and tangent rows' impulse and the torsional and rolling rows' angular impulse (0 where not finite)
  template <typename V>
  static void keep(const V* lambda, int dims, const V* d, V* P) {
    V x[6] = {};
    for (int e = 0; e < dims; ++e) x[e] = lambda[e];
    for (int half = 0; half < 2; ++half) {
      const V* l = x + 3 * half;
      V* out = P + 3 * half;
      for (int m = 0; m < 3; ++m) out[m] = l[0] * d[m] + l[1] * d[3 + m] + l[2] * d[6 + m];
      const Mask<V> ok = both(both(finite(out[0]), finite(out[1])), finite(out[2]));
      for (int m = 0; m < 3; ++m) out[m] = select<V>(ok, out[m], V{});
    }
  }
};

}  // namespace novaphy
