// An applied wrench moved to another point, written once over the number type (kernels/number.h):
// how a body's wrench (body_f: a force through its centre of mass and a torque) reaches the link that
// carries it, on the dense route and in the blocks alike.
#pragma once

#include "kernels/number.h"

namespace novaphy {

// a force f [3] through the point r [3] (relative to the new point) and a torque t [3]: their wrench
// about the new point, added to torque [3] and force [3]
template <typename V>
inline void add_wrench_about(const V* f, const V* t, const V* r, V* torque, V* force) {
  torque[0] += t[0] + r[1] * f[2] - r[2] * f[1];
  torque[1] += t[1] + r[2] * f[0] - r[0] * f[2];
  torque[2] += t[2] + r[0] * f[1] - r[1] * f[0];
  for (int m = 0; m < 3; ++m) force[m] += f[m];
}

}  // namespace novaphy
