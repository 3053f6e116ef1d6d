// The limit rows of a Revolute or Prismatic joint's range, or of a tendon's length: one row per side, over the
// number type (kernels/number.h: one world, or a SIMD block's lanes). With sign +1 for the lower limit and -1 for
// the upper, gap = sign (x - limit) >= 0 inside the range (x: the coordinate or the length) and the row keeps
// sign x_dot >= its target: a Unilateral row (kernels/pgs.h project_unilateral). Hard (erp, slop) or soft as MuJoCo's
// (soft_row.h) by its solref.
#pragma once

#include "engine/solver/parts/soft_row.h"
#include "engine/solver/parts/warm_start.h"
#include "kernels/pgs.h"

namespace novaphy {

// (warm start and kept impulse: KeptImpulseRow)
struct LimitRow : KeptImpulseRow {
  static constexpr RowKind kKind = RowKind::Unilateral;

  // the side's sign: +1 for the lower limit (side 0), -1 for the upper
  static int sign(int side) { return side == 0 ? 1 : -1; }
  // the side's gap: >= 0 inside the range
  template <typename V>
  static V gap(const V& x, const V& limit, int side) {
    return static_cast<Element<V>>(sign(side)) * (x - limit);
  }

  // the side's row is on this step where its limit is finite and, for a hard row, the coordinate would cross it
  // within the step (x_dot: the coordinate's velocity); for a soft one, is past it (MuJoCo's rule: the coordinate
  // may pass the limit within a step, its row pushes it back)
  template <typename V>
  static Mask<V> on(const V& limit, const V& gap, const V& x_dot, int side, const V& dt, const Mask<V>& soft) {
    const Mask<V> crosses = gap + dt * (static_cast<Element<V>>(sign(side)) * x_dot) < 0;
    return both<Mask<V>>(finite(limit), either<Mask<V>>(both<Mask<V>>(soft, gap < 0), but_not<Mask<V>>(crosses, soft)));
  }

  // close a gap in one step; push a penetration beyond the slop out at erp / dt
  template <typename V, typename Settings>
  static V target(const V& gap, const Settings& p, const V& dt) {
    const V depth = -gap - static_cast<Element<V>>(p.linear_slop);
    const V zero{};
    return select<V>(gap >= 0, -gap / dt, static_cast<Element<V>>(p.erp) * select<V>(depth > 0, depth, zero) / dt);
  }

  // a soft side's cfm and target (the row on: the coordinate past the limit, gap < 0), v its velocity sign x_dot at
  // the step's start
  static SoftRow soft(Scalar gap, Scalar v, const Softness& s, Scalar dt) {
    return soft_row(s.solref, s.solimp, s.weight, gap, gap, v, dt);
  }
};

}  // namespace novaphy
