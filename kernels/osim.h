// The inverse operational-space inertia of every link, Omega_i = J_i H^-1 J_i^T (6 x 6, link coordinates,
// [angular; linear]; J_i the link's Jacobian, H the joint-space inertia with armature): how a link accelerates under
// a unit wrench on it alone. The O(n) recursion over the articulated-body factor (Featherstone RBDA, section 7.3;
// Wensing, Featherstone and Orin, "A reduced-order recursive algorithm for the computation of the operational-space
// inertia matrix", ICRA 2012) and its dense reference twin.
#pragma once

#include <vector>

#include "kernels/articulation.h"

namespace novaphy {

// O(n): aba_factor (armature only), then outward
//   Omega_i = S_i D_i^-1 S_i^T + Q_i^T Omega_parent Q_i,   Q_i = Xup_i^T (1 - U_i D_i^-1 S_i^T),
// with Omega = 0 above a root (the world does not move). Q_i carries a wrench on link i to the wrench its
// articulated parent feels; Q_i^T carries the parent's acceleration back to link i's.
// inputs:  s after forward_kinematics
// outputs: Omega [link]; s.IC, s.U, s.D_inv as aba_factor leaves them
// returns -1, or the link whose articulated inertia S^T IA S is not positive definite
int osim_inverse(const ArticulationView& art, ArticulationScratch& s, std::vector<Mat6>& Omega);

// reference twin, O(n^3): H and the link Jacobians from mass_matrix_gemm, a dense Cholesky of H and six solves a
// link. inputs, outputs as osim_inverse (s.H holds the factor, s.link_jacobian the Jacobians);
// returns -1, or the dof whose pivot is not positive
int osim_inverse_ref(const ArticulationView& art, ArticulationScratch& s, std::vector<Mat6>& Omega);

}  // namespace novaphy
