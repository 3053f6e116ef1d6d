// A dof's dry friction (frictionloss): one row per dof with J = e_k driving its velocity to zero with an impulse of
// at most frictionloss dt either way, over the number type (kernels/number.h): a Bounded row (kernels/pgs.h
// project_bounded). Hard, or soft as MuJoCo's (soft_row.h) by its solref.
#pragma once

#include "engine/solver/parts/soft_row.h"
#include "engine/solver/parts/warm_start.h"
#include "kernels/pgs.h"

namespace novaphy {

// (warm start and kept impulse: KeptImpulseRow)
struct FrictionLossRow : KeptImpulseRow {
  static constexpr RowKind kKind = RowKind::Bounded;

  // the dof has a row: its frictionloss is positive
  template <typename V>
  static Mask<V> on(const V& frictionloss) {
    return frictionloss > 0;
  }

  // the largest impulse either way; its target velocity is 0
  template <typename V>
  static V bound(const V& frictionloss, const V& dt) {
    return frictionloss * dt;
  }

  // a soft row's cfm and target (MuJoCo's: no stiffness, the impedance at 0), v the dof's velocity at the step's
  // start
  static SoftRow soft(Scalar v, const Softness& s, Scalar dt) {
    return soft_row(s.solref, s.solimp, s.weight, 0, 0, v, dt);
  }
};

}  // namespace novaphy
