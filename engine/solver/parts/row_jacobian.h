// A row's Jacobian entries for a point riding on a link: what the rows of contacts and body equalities are made of,
// over the number type (kernels/number.h).
#pragma once

#include "kernels/spatial.h"

namespace novaphy {

// u [3]: the velocity of the point p [3] moved by the motion s [6] ([angular; linear], about the point p
// is measured from); a contact row's Jacobian entry for that motion along a direction d is d . u
template <typename V>
inline void point_velocity(const V* s, const V* p, V* u) {
  u[0] = s[3] + s[1] * p[2] - s[2] * p[1];
  u[1] = s[4] + s[2] * p[0] - s[0] * p[2];
  u[2] = s[5] + s[0] * p[1] - s[1] * p[0];
}

// d . (the velocity of the point p moved by the motion s), or with p null d . (its angular velocity): a
// row's Jacobian entry for the dof of motion s (the islands' rows, one double at a time)
inline Scalar motion_along(const Scalar* s, const Scalar* p, const Scalar* d) {
  Scalar u[3] = {s[0], s[1], s[2]};
  if (p) point_velocity(s, p, u);
  return d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
}

}  // namespace novaphy
