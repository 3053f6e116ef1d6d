// Articulated-body algorithm, O(n) forward dynamics (Featherstone RBDA, section 7.3, table 7.1).
#pragma once

#include "kernels/articulation.h"

namespace novaphy {

// inputs:  s after forward_kinematics + forward_velocity, tau (generalised forces, passive included),
//          gravity (world), body_f ([body][6] world wrenches or nullptr)
// outputs: qdd; s.IC holds the articulated inertias IA, s.pA the articulated bias forces
// returns -1, or the link whose articulated inertia S^T IA S is not positive definite
int aba(const ArticulationView& art, const Scalar* tau, const Vec3& gravity, const Scalar* body_f,
        ArticulationScratch& s, Scalar* qdd);

}  // namespace novaphy
