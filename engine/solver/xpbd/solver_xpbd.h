// SolverXPBD: every body in maximal coordinates, its constraints held at the position level with compliance
// (XPBD: Macklin, Mueller, Chentanez 2016; rigid bodies: Mueller et al. 2020, "Detailed Rigid Body Simulation with
// Extended Position Based Dynamics"). Per world and substep h = dt / substeps:
//   predict (v += h (g + f / m), w += h I^-1 (tau - w x I w), x += h v, q turned by h w) ->
//   `iterations` passes over the constraints (each locked or limited axis, engine/solver/maximal/constraints.h: the
//   rotation first, then the anchors' offset; a distance; then each axis's stiffness, AxisSpring's drives, springs
//   and servos, towards its rest with compliance 1 / K) and the contacts (penetration, then static friction), each a
//   position correction of compliance alpha / h^2 -> velocities from the positions -> the velocity pass: contacts'
//   dynamic friction and restitution, each axis's damping and constant force (implicitly over h) -> angular damping
// A constraint's compliance is the joint's own (model.joint_compliance) plus the settings' joint_*_compliance.
#pragma once

#include <vector>

#include "engine/solver/maximal/maximal_solver.h"

namespace novaphy {

class SolverXPBD : public MaximalSolver {
 public:
  explicit SolverXPBD(const Model& model, const SolverXPBDSettings& settings = {});

  SolverXPBDSettings settings;

 private:
  // a contact of the step: its bodies' slots, its points in their bodies' frames (about the COM), its normal
  struct XContact {
    int a = -1, b = -1;
    Vec3 r_a = Vec3::Zero(), r_b = Vec3::Zero(), n = Vec3::Zero();
    Scalar mu = 0, restitution = 0;
    Scalar lambda_n = 0, lambda_t = 0;  // this substep's
    Scalar approach = 0;                // the normal velocity before the substep
    Scalar depth = 0;                   // the penetration at the step's start (contact_depth)
    Scalar allowed = 0;                 // the penetration left this substep (max_depenetration_velocity)
  };
  struct Scratch {
    std::vector<BodyMotion> bodies, before;  // now, and at the substep's start
    std::vector<int> body;                   // each slot's body
    std::vector<XContact> contacts;
    std::vector<Scalar> lambda;       // per constraint of the world: rotation, offset (or distance), 6 axes' stiffness
    std::vector<AxisSpring> springs;  // per constraint of the world: each axis's, for the step
  };
  void step_world(int w, const StepInput& step, int thread) override;
  void check_settings() const override { settings.check(); }
  int thread_count() const override { return settings.num_threads; }
  GuardSettings guard_settings() const override {
    return {settings.on_divergence, settings.divergence_speed, settings.divergence_depth};
  }
  // one substep's pieces
  void predict(int w, const StepInput& step, Scalar h, Scratch& s) const;
  // constraint c's rotation, offset or distance, then its axes' stiffnesses (springs [6])
  void solve_constraint(const MaximalConstraint& c, const AxisSpring* springs, const State& in, Scalar h,
                        Scalar* lambda, Scratch& s) const;
  // an axis's coordinate as its joint's (a Revolute angle winds on from the step's start)
  Scalar wound(const MaximalConstraint& c, int k, const State& in, Scalar coordinate) const;
  // a contact's penetration undone (its normal multiplier accumulating into lambda_n), then, once every contact's
  // was, its static friction: the points' relative tangential motion over the substep undone while
  // lambda_t + its multiplier stays below mu lambda_n
  void solve_contact(XContact& c, Scratch& s) const;
  void hold_contact(XContact& c, Scratch& s) const;
  void velocity_pass(int w, Scalar h, Scratch& s) const;

  std::vector<Scratch> scratch_;  // per thread
};

}  // namespace novaphy
