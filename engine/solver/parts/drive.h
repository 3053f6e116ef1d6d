// The implicit joint-space forces of one dof: its damper, spring and PD drive, evaluated at the end of
// the step (semi-implicit Euler with the stiff terms implicit), so that
//   (H + dt D + dt^2 K) qdd = tau - bias - D qd + kd (v_t - qd) - K_s (q_end - q_ref) + ke (q_t - q_end)
// with D = damping + kd, K = stiffness + ke, q_end = q + dt qd; and the actuators' stiffness K_a and damping D_a
// (engine/model/actuator.h) likewise. Written once over the number type
// (kernels/number.h) for the dense route and the blocks.
#pragma once

#include "kernels/number.h"

namespace novaphy {

// (references: the blocks' lanes are read where they lie, not copied)
template <typename V>
struct DofDrive {
  const V &damping, &kd, &target_vel;  // the damper and the velocity drive
  const V &stiffness, &q_ref;          // the spring (a dof with a coordinate: Revolute, Prismatic)
  const V &ke, &target_pos;            // the position drive (likewise)
};

// rhs += the dof's forces at the end of the step, given its bias force and, for a dof with a coordinate,
// q (nullptr: none); returns the diagonal dt D + dt^2 K they add to H
template <typename V>
inline V add_dof_forces(const DofDrive<V>& d, const V& bias, const V& qd, const V* q, const V& dt, V& rhs) {
  rhs += -bias - d.damping * qd + d.kd * (d.target_vel - qd);
  V diagonal = dt * (d.damping + d.kd);
  if (!q) return diagonal;
  const V q_end = *q + dt * qd;
  rhs += -d.stiffness * (q_end - d.q_ref) + d.ke * (d.target_pos - q_end);
  diagonal += dt * dt * (d.stiffness + d.ke);
  return diagonal;
}

// rhs += the actuators' -K_a q_end - D_a qd at the end of the step on a dof of coordinate q; returns the
// diagonal dt D_a + dt^2 K_a they add to H
template <typename V>
inline V add_actuator_forces(const V& stiffness, const V& damping, const V& q, const V& qd, const V& dt, V& rhs) {
  rhs += -stiffness * (q + dt * qd) - damping * qd;
  return dt * damping + dt * dt * stiffness;
}

}  // namespace novaphy
