// Recursive Newton-Euler inverse dynamics (Featherstone RBDA, section 5.3, table 5.1).
#pragma once

#include "kernels/articulation.h"

namespace novaphy {

// external wrench on link i in link coordinates, from body_f = [f at the centre of mass; torque]
// in world coordinates (nullptr means no applied wrenches)
Vec6 link_external_force(const ArticulationView& art, const ArticulationScratch& s, const Scalar* body_f, int i);

// inputs:  s after forward_kinematics + forward_velocity, qdd, gravity (world), body_f ([body][6] or nullptr)
// outputs: tau = H qdd + C qd + g - J^T f_ext (H with the armature, no passive forces), s.a, s.f
void rnea(const ArticulationView& art, const Scalar* qdd, const Vec3& gravity, const Scalar* body_f,
          ArticulationScratch& s, Scalar* tau);

// C = d bias / d qd at qd (dof x dof, sized here): the Jacobian of the Coriolis and centrifugal forces.
// RNEA at qdd = 0 is quadratic in qd plus terms free of qd, so the central difference
// (bias(qd + e_k) - bias(qd - e_k)) / 2 is exact: 2 n velocity passes and RNEAs, O(n^2).
// inputs: s after forward_kinematics; outputs: C, s.v and s.c at qd again
void bias_velocity_jacobian(const ArticulationView& art, const Scalar* qd, ArticulationScratch& s, MatX& C);

// joint damping and stiffness as generalised forces: tau_passive = -damping qd - stiffness (q - q_ref),
// stiffness acting on Revolute and Prismatic joints
void passive_force(const ArticulationView& art, const Scalar* q, const Scalar* qd, Scalar* tau_passive);

}  // namespace novaphy
