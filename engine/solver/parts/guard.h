// The divergence guard's test, written once over the number type (kernels/number.h): a world
// diverged when a coordinate or velocity after the step is not finite, a dof is faster than `speed`, or its
// kinetic energy per kilogram, 1/2 sum_k weight_k qd_k^2 (weight: the mass matrix's diagonal at joint_q0 over the
// world's mass), passes `energy` (compared in double, whatever the lanes' precision).
#pragma once

#include "kernels/number.h"

namespace novaphy {

// diverged [lanes]: per lane, whether q_next [nq] and qd [nv] diverged; weight [nv] as above
template <typename V>
inline void divergence_test(const V* q_next, int nq, const V* qd, const V* weight, int nv, Scalar speed, Scalar energy,
                            bool* diverged) {
  Mask<V> ok = finite(splat<V>(0));
  V fastest{}, twice_energy{};
  for (int k = 0; k < nq; ++k) ok = both(ok, finite(q_next[k]));
  for (int k = 0; k < nv; ++k) {
    const V v = magnitude(qd[k]);
    ok = both(ok, finite(v));
    fastest = select<V>(v > fastest, v, fastest);
    twice_energy = twice_energy + weight[k] * qd[k] * qd[k];
  }
  for (int l = 0; l < NumberTraits<V>::lanes; ++l)
    diverged[l] = !lane_set<V>(ok, l) || static_cast<Scalar>(lane(fastest, l)) > speed ||
                  0.5 * static_cast<Scalar>(lane(twice_energy, l)) > energy;
}

}  // namespace novaphy
