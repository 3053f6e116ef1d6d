// Position corrections between two bodies of a world, as XPBD makes them (Mueller et al. 2020, "Detailed Rigid Body
// Simulation with Extended Position Based Dynamics", section 3.3): a scalar constraint C along a direction at two
// points, or a rotation, corrected with compliance alpha_h (alpha / h^2) and its multiplier lambda accumulating,
//   delta lambda = (-C - alpha_h lambda) / (w_a + w_b + alpha_h),
// w a body's generalised inverse mass. SolverXPBD corrects every constraint and contact so; SolverSemiImplicit holds
// its rigid joints so after integrating (a position pass that leaves the velocities alone). Bodies are slots of a
// world's (engine/solver/maximal/constraints.h); -1 is the world.
#pragma once

#include <vector>

#include "engine/model/model.h"
#include "engine/solver/maximal/constraints.h"

namespace novaphy {

// the generalised inverse mass of slot i at point p along the unit direction n (0 for the world)
Scalar inverse_mass(const std::vector<BodyMotion>& bodies, int i, const Vec3& p, const Vec3& n);
// an impulse p on b at its point pb (a: -p at pa), into their velocities
void apply_impulse(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& pa, const Vec3& pb, const Vec3& p);
// the scalar constraint C along the unit direction n (C grows as b's point pb moves along n relative to a's point pa)
// corrected towards 0; returns the multiplier's change
Scalar push(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& pa, const Vec3& pb, const Vec3& n, Scalar C,
            Scalar alpha_h, Scalar* lambda, Scalar relaxation);
// the same for a rotation of b about n relative to a
void turn(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& n, Scalar C, Scalar alpha_h, Scalar* lambda,
          Scalar relaxation);
// b's point pb moved by the vector `correction` relative to a's point pa (push along its direction, by its length)
Scalar correct_position(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& pa, const Vec3& pb,
                        const Vec3& correction, Scalar alpha_h, Scalar* lambda, Scalar relaxation);
// b turned by the rotation vector `correction` relative to a
void correct_rotation(std::vector<BodyMotion>& bodies, int a, int b, const Vec3& correction, Scalar alpha_h,
                      Scalar* lambda, Scalar relaxation);

// what a constraint's position pass reads: its compliances (per h^2) and relaxations
struct HoldSettings {
  Scalar alpha_linear = 0, alpha_angular = 0;
  Scalar relax_linear = 1, relax_angular = 1;
};
// constraint c (its bodies' slots a, b) held where its axes allow: its locked and limited rotation first, then its
// anchors' offset, or its distance; lambda [2]: the rotation's and the offset's multipliers
void hold_constraint(const Model& model, const MaximalConstraint& c, int a, int b, const HoldSettings& hold,
                     Scalar* lambda, std::vector<BodyMotion>& bodies);

}  // namespace novaphy
