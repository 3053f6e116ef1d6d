// Forward kinematics and link velocities (Featherstone RBDA, section 4.1 and table 5.1).
#pragma once

#include "kernels/articulation.h"

namespace novaphy {

// inputs:  q (articulation coordinates)
// outputs: s.X_up, s.X_world, s.Xup, s.S (link coordinates), s.I
void forward_kinematics(const ArticulationView& art, const Scalar* q, ArticulationScratch& s);

// inputs:  qd (articulation dofs), s after forward_kinematics
// outputs: s.v (link velocities), s.c (velocity-product accelerations)
void forward_velocity(const ArticulationView& art, const Scalar* qd, ArticulationScratch& s);

}  // namespace novaphy
