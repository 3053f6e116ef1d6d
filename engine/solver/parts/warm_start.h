// What every row kind but a contact's shares: the share of its last impulse it starts from, and the impulse it
// keeps for the next step (a contact's rows: contact_rows.h).
#pragma once

#include "engine/solver/settings.h"
#include "kernels/number.h"

namespace novaphy {

// the share of its last step's impulses a world's rows start from: all of them where its last sweeps converged
// (stopped at one that moved no row beyond pgs_tolerance), warmstarting_factor of them where they ran out (an
// error left by sweeps that ran out, carried whole from step to step, can build up), none without warm starting
template <typename V, typename Settings>
inline V warm_share(const Mask<V>& converged, const Settings& p) {
  using E = Element<V>;
  if (!p.use_warmstarting) return V{};
  return select<V>(converged, splat<V>(E(1)), splat<V>(static_cast<E>(p.warmstarting_factor)));
}

// a row that starts from its world's warm_share of the impulse it kept, and keeps its own for the next step where it
// was on and is finite, else 0 (LimitRow, FrictionLossRow, EqualityRow)
struct KeptImpulseRow {
  template <typename V>
  static V warm(const V& kept, const V& share) {
    return share * kept;
  }
  template <typename V>
  static V keep(const V& lambda, const Mask<V>& on) {
    return select<V>(both(on, finite(lambda)), lambda, V{});
  }
};

}  // namespace novaphy
