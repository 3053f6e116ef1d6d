// A contact's softness: MuJoCo's soft constraint (solref, solimp; soft_row.h) over the lanes of a contact's rows,
// with pos - margin in place of pos. A contact whose deciding solref is (0, 0) is rigid
// (ContactRows::rigid_normal_target, contact_rows.h). Where a contact's softness is computed: contact_pair
// (contact_material.h) takes the deciding solref and solimp from the two shapes as MuJoCo combines geoms, and K and B
// from that solref at the step's dt, once per pair of materials; contact_softness here the rest, per contact and
// step, from its depth.
#pragma once

#include <algorithm>
#include <cmath>

#include "engine/solver/parts/contact_material.h"
#include "engine/solver/parts/soft_row.h"
#include "kernels/number.h"

namespace novaphy {

// a contact's softness over the number type (kernels/number.h): whether it is soft, the normal row's cfm R (0 while
// the contact is inactive, farther than margin - gap), the friction rows' (R / impratio), MuJoCo's B, and K imp
// (pos - margin)
template <typename V>
struct ContactSoftness {
  Mask<V> soft{};
  V cfm_normal{}, cfm_friction{};
  V damping{};        // B
  V spring{};         // K imp (pos - margin), pos = -depth: the acceleration it pushes out at (< 0)
  V active_margin{};  // margin - gap: a contact nearer than this is active
};

// a contact's softness from its pair at penetration `depth`; weight_a, weight_b: the shapes' bodies'
// invweight0 (translational; 0 for a static body, contact_weight), impratio the model's
inline ContactSoftness<Scalar> contact_softness(const ContactPair& pair, Scalar weight_a, Scalar weight_b,
                                                Scalar impratio, Scalar depth) {
  ContactSoftness<Scalar> s;
  if (!pair.soft) return s;
  s.soft = true;
  s.active_margin = pair.active_margin;
  const Scalar x = -depth - s.active_margin;  // pos - margin: < 0 where active
  if (x >= 0) return s;
  const Scalar imp = impedance(pair.solimp, x);
  s.cfm_normal = soft_cfm(imp, weight_a + weight_b);
  s.cfm_friction = s.cfm_normal / impratio;
  s.damping = pair.damping;
  s.spring = pair.stiffness * imp * x;
  return s;
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

}  // namespace novaphy
