// A dof's dry friction (frictionloss): one row per dof with J = e_k driving its velocity to zero with an impulse of
// at most frictionloss dt either way, over the number type (kernels/number.h): a Bounded row (kernels/pgs.h
// project_bounded).
#pragma once

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
};

}  // namespace novaphy
