// A contact's material: what it takes from its two shapes (friction by the model's FrictionRule, restitution, and
// the solref/solimp its softness is made from, engine/solver/parts/contact_softness.h), and the table of them a step
// reads (ShapeContacts: a model of replicated robots has few distinct materials).
#pragma once

#include <algorithm>
#include <cmath>

#include "engine/model/model.h"
#include "engine/solver/parts/soft_row.h"

namespace novaphy {

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
// the sliding friction coefficient alone
inline Scalar contact_friction(const Model& model, int a, int b) { return contact_friction_of(model, a, b).mu; }
inline Scalar contact_restitution(const ContactMaterial& a, const ContactMaterial& b) {
  return std::max(a.restitution, b.restitution);
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
  if (!is_soft(solref)) return pair;
  pair.soft = true;
  pair.active_margin = std::max(a.margin, b.margin) - std::max(a.gap, b.gap);
  const SoftReference k = soft_reference(solref, pair.solimp, dt);
  pair.stiffness = k.stiffness;
  pair.damping = k.damping;
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

// a shape's body's invweight0 (0: a static body), as contact_softness takes it
inline Scalar contact_weight(const Model& model, int shape) {
  const int body = model.shape_body[shape];
  return body < 0 ? Scalar(0) : model.body_invweight0[2 * body];
}

}  // namespace novaphy
