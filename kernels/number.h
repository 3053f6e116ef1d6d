// The number types a part of the step (and a kernel's shared steps, such as the sweeps' projections) is written
// over: a plain Scalar for one articulation on the dense route, or Lanes<T> for a block of worlds, one per lane.
// A part uses only arithmetic, comparisons and the few operations below, so one text serves both: a world steps
// by the same formula on either route.
#pragma once

#include <cmath>
#include <limits>
#include <type_traits>

#include "kernels/lanes.h"
#include "kernels/spatial.h"

namespace novaphy {

template <typename V>
struct NumberTraits {  // a plain number: one world
  using Element = V;
  using Mask = bool;
  static constexpr int lanes = 1;
};
template <>
struct NumberTraits<Lanes<float>> {
  using Element = float;
  using Mask = IntLanes<float>;
  static constexpr int lanes = kLanes<float>;
};
template <>
struct NumberTraits<Lanes<double>> {
  using Element = double;
  using Mask = IntLanes<double>;
  static constexpr int lanes = kLanes<double>;
};

template <typename V>
using Mask = typename NumberTraits<V>::Mask;
template <typename V>
using Element = typename NumberTraits<V>::Element;

// m ? a : b, lane by lane
template <typename V>
inline V select(const Mask<V>& m, const V& a, const V& b) {
  return m ? a : b;
}

// a and b, lane by lane
template <typename M>
inline M both(const M& a, const M& b) {
  if constexpr (std::is_same_v<M, bool>)
    return a && b;
  else
    return a & b;
}

// a or b, lane by lane
template <typename M>
inline M either(const M& a, const M& b) {
  if constexpr (std::is_same_v<M, bool>)
    return a || b;
  else
    return a | b;
}

// a and not b, lane by lane
template <typename M>
inline M but_not(const M& a, const M& b) {
  if constexpr (std::is_same_v<M, bool>)
    return a && !b;
  else
    return a & ~b;
}

// whether any lane of m is set
template <typename V>
inline bool any_set(const Mask<V>& m) {
  if constexpr (std::is_same_v<Mask<V>, bool>)
    return m;
  else
    return any_lane<Element<V>>(m);
}

// |x|; a NaN stays a NaN
template <typename V>
inline V magnitude(const V& x) {
  return x < 0 ? -x : x;
}

// finite: |x| <= the largest number (false for inf and NaN)
template <typename V>
inline Mask<V> finite(const V& x) {
  return magnitude(x) <= std::numeric_limits<Element<V>>::max();
}

// lane l of x (x itself for a plain number)
template <typename V>
inline Element<V> lane(const V& x, int l) {
  if constexpr (std::is_arithmetic_v<V>) {
    static_cast<void>(l);
    return x;
  } else {
    return x[l];
  }
}
template <typename V>
inline bool lane_set(const Mask<V>& m, int l) {
  if constexpr (std::is_same_v<Mask<V>, bool>) {
    static_cast<void>(l);
    return m;
  } else {
    return m[l] != 0;
  }
}

// +1 or -1 with the sign of x, lane by lane (copysign: -0 gives -1)
template <typename V>
inline V unit_sign(const V& x) {
  if constexpr (std::is_arithmetic_v<V>) {
    return std::copysign(V(1), x);
  } else {
    V s;
    for (int l = 0; l < NumberTraits<V>::lanes; ++l) s[l] = std::copysign(Element<V>(1), x[l]);
    return s;
  }
}

// the square root, lane by lane
template <typename V>
inline V root(const V& x) {
  if constexpr (std::is_arithmetic_v<V>)
    return std::sqrt(x);
  else
    return lane_sqrt<Element<V>>(x);
}

// a number of every lane equal to x
template <typename V>
inline V splat(Element<V> x) {
  return V{} + x;
}

}  // namespace novaphy
