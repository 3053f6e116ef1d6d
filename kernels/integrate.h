// Semi-implicit joint integration: q+ = q (+) dt qd+, with the quaternion exponential map and
// renormalisation for Ball (angular velocity in the child frame: q * exp(dt w / 2)) and Free
// (angular velocity in the parent frame: exp(dt w / 2) * q).
#pragma once

#include "kernels/articulation.h"

namespace novaphy {

// inputs:  q, qd (articulation coordinates and dofs), dt
// outputs: q_out (may alias q)
void integrate_joints(const ArticulationView& art, const Scalar* q, const Scalar* qd, Scalar dt, Scalar* q_out);

}  // namespace novaphy
