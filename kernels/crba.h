// Composite-rigid-body algorithm for the joint-space inertia matrix (Featherstone RBDA, section 6.2).
#pragma once

#include "kernels/articulation.h"

namespace novaphy {

// inputs:  s after forward_kinematics
// outputs: s.H (dof x dof, armature on the diagonal), s.IC
void crba(const ArticulationView& art, ArticulationScratch& s);

// the same H as the product sum_i J_i^T I_i J_i of link Jacobians (the use_tile_gemm path;
// outputs s.H and s.link_jacobian)
void mass_matrix_gemm(const ArticulationView& art, ArticulationScratch& s);

}  // namespace novaphy
