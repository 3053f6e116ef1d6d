// Articulated-body algorithm, O(n) forward dynamics (Featherstone RBDA, section 7.3, table 7.1),
// split like crba + Cholesky into a factor (the articulated inertias, which depend on q only) and
// O(n) passes that use it.
#pragma once

#include "kernels/articulation.h"

namespace novaphy {

// the articulated inertias of M = H + diag(diagonal) at the pose of s (after forward_kinematics):
// s.IC = IA, s.U = IA S, s.D_inv = (S^T IA S + armature + diagonal)^-1; diagonal per dof of the
// articulation or nullptr. Returns -1, or the link whose S^T IA S is not positive definite.
int aba_factor(const ArticulationView& art, const Scalar* diagonal, ArticulationScratch& s);

// solves M x = b in place (x holds b on entry) in O(n) with the factor of aba_factor: the ABA
// passes at zero velocity and gravity, the counterpart of cholesky_solve
void aba_solve(const ArticulationView& art, ArticulationScratch& s, Scalar* x);

// forward dynamics: aba_factor (armature only), then the passes with velocity products, gravity and
// applied wrenches.
// inputs:  s after forward_kinematics + forward_velocity, tau (generalised forces, passive included),
//          gravity (world), body_f ([body][6] world wrenches or nullptr)
// outputs: qdd; s.IC holds the articulated inertias IA, s.pA the articulated bias forces
// returns -1, or the link whose articulated inertia S^T IA S is not positive definite
int aba(const ArticulationView& art, const Scalar* tau, const Vec3& gravity, const Scalar* body_f,
        ArticulationScratch& s, Scalar* qdd);

}  // namespace novaphy
