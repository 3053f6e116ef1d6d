// A fixed tendon (model.h): its length and velocity, and the force of its spring and damper, written once
// for the step and the whole-model evaluations. Forces along a tendon (the spring's, the damper's and those
// of actuators on it) are taken explicitly: they couple the tendon's dofs, which the step's diagonal
// implicit terms cannot.
#pragma once

#include "engine/model/model.h"

namespace novaphy {

// tendon t's length at the coordinates q, or its velocity at the velocities qd (`dof`)
inline Scalar tendon_length(const Model& model, int t, const Scalar* q) {
  Scalar length = 0;
  for (int e = model.tendon_start[t]; e < model.tendon_start[t + 1]; ++e)
    length += model.tendon_coef[e] * q[model.tendon_coord[e]];
  return length;
}
inline Scalar tendon_velocity(const Model& model, int t, const Scalar* qd) {
  Scalar velocity = 0;
  for (int e = model.tendon_start[t]; e < model.tendon_start[t + 1]; ++e)
    velocity += model.tendon_coef[e] * qd[model.tendon_dof[e]];
  return velocity;
}

// the force along tendon t of its spring and damper at that length and velocity
inline Scalar tendon_passive_force(const Model& model, int t, Scalar length, Scalar velocity) {
  return -model.tendon_stiffness[t] * (length - model.tendon_rest_length[t]) - model.tendon_damping[t] * velocity;
}

// tau += the joint forces of `force` along tendon t
inline void add_tendon_force(const Model& model, int t, Scalar force, Scalar* tau) {
  for (int e = model.tendon_start[t]; e < model.tendon_start[t + 1]; ++e)
    tau[model.tendon_dof[e]] += model.tendon_coef[e] * force;
}

}  // namespace novaphy
