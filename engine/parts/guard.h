// The divergence guard's test, written once over the number type (engine/parts/number.h): a world
// diverged when a coordinate or velocity after the step is not finite or a dof is faster than `speed`
// (compared in double, whatever the lanes' precision).
#pragma once

#include "engine/parts/number.h"

namespace novaphy {

// diverged [lanes]: per lane, whether q_next [nq] and qd [nv] diverged
template <typename V>
inline void divergence_test(const V* q_next, int nq, const V* qd, int nv, Scalar speed, bool* diverged) {
  Mask<V> ok = finite(splat<V>(0));
  V fastest{};
  for (int k = 0; k < nq; ++k) ok = both(ok, finite(q_next[k]));
  for (int k = 0; k < nv; ++k) {
    const V v = magnitude(qd[k]);
    ok = both(ok, finite(v));
    fastest = select<V>(v > fastest, v, fastest);
  }
  for (int l = 0; l < NumberTraits<V>::lanes; ++l)
    diverged[l] = !lane_set<V>(ok, l) || static_cast<Scalar>(lane(fastest, l)) > speed;
}

}  // namespace novaphy
