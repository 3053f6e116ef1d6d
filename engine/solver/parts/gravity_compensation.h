// Gravity compensation, MuJoCo's body gravcomp: a force -gravcomp m g through a body's centre of mass (g its world's
// gravity), applied as the wrenches of the state's body_f are. Written once here: SolverFeatherstone and the
// evaluation functions apply body_f with it added (with_gravity_compensation), the solvers in maximal coordinates
// add it body by body (gravity_compensation).
#pragma once

#include <algorithm>
#include <vector>

#include "engine/model/model.h"

namespace novaphy {

// some body of the model has its gravity compensated
inline bool compensates_gravity(const Model& model) {
  return std::any_of(model.body_gravcomp.begin(), model.body_gravcomp.end(), [](Scalar x) { return x != 0; });
}

// body b's compensating force (world frame, through its centre of mass)
inline Vec3 gravity_compensation(const Model& model, int b) {
  const int w = std::max(0, model.body_world[b]);
  const Vec3 g(model.world_gravity[3 * w], model.world_gravity[3 * w + 1], model.world_gravity[3 * w + 2]);
  return -(model.body_gravcomp[b] * model.body_mass[b]) * g;
}

// the wrenches body_f ([force at the centre of mass; torque] per body) with every body's compensating force added,
// into out (its storage kept from call to call)
inline void with_gravity_compensation(const Model& model, const std::vector<Scalar>& body_f, std::vector<Scalar>& out) {
  out.assign(body_f.begin(), body_f.end());
  for (int b = 0; b < model.body_count; ++b)
    if (model.body_gravcomp[b] != 0) {
      const Vec3 f = gravity_compensation(model, b);
      for (int m = 0; m < 3; ++m) out[6 * static_cast<size_t>(b) + m] += f[m];
    }
}

}  // namespace novaphy
