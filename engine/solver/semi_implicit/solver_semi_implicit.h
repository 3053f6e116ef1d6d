// SolverSemiImplicit: every body in maximal coordinates, the seed's sequential-impulse pipeline over bodies.
//   per world: external forces (gravity, body_f, joint_f, gyroscopic) -> velocity rows: each constraint's locked,
//   limited and driven axes (engine/solver/maximal/constraints.h), each contact's normal and friction rows ->
//   PGS sweeps (sequential impulses, Catto 2005) -> semi-implicit integration of every body (x += dt v, q turned by
//   dt w, renormalised) -> position passes over the rigid joints (engine/solver/maximal/corrections.h: the drift the
//   rows' Baumgarte term leaves at speed taken out of the positions, the velocities left alone)
// The rows are the parts SolverFeatherstone's rows are (engine/solver/parts/: ContactRows, LimitRow, EqualityRow),
// with Jacobians over the two bodies' velocities; a compliant or driven axis is a soft row (AxisSpring taken
// implicitly). Worlds are stepped one per thread at a time (engine/solver/maximal/maximal_solver.h).
#pragma once

#include <vector>

#include "engine/solver/maximal/maximal_solver.h"
#include "kernels/pgs.h"

namespace novaphy {

// a velocity row between two bodies (slots among their world's; -1: the world or a static body):
// its velocity is lin_a . v_a + ang_a . w_a + lin_b . v_b + ang_b . w_b
struct BodyRow {
  int a = -1, b = -1;
  Vec3 lin_a = Vec3::Zero(), ang_a = Vec3::Zero(), lin_b = Vec3::Zero(), ang_b = Vec3::Zero();
  Vec3 turn_a = Vec3::Zero(), turn_b = Vec3::Zero();  // the inverse inertias times ang_a, ang_b
  Scalar inv_mass = 0;                                // 1 / (J M^-1 J^T + cfm)
  RowKind kind = RowKind::Bounded;
  Scalar bound = 0;  // Bounded: the largest |impulse|
  int normal = -1;   // FrictionPair, FrictionOne: the row of the normal impulse
  Scalar mu = 0;
  Scalar target = 0, cfm = 0, lambda = 0;
  Scalar* kept = nullptr;  // where its impulse is kept for the next step (a constraint's; nullptr: a contact's)
};

class SolverSemiImplicit : public MaximalSolver {
 public:
  explicit SolverSemiImplicit(const Model& model, const SolverSemiImplicitSettings& settings = {});

  SolverSemiImplicitSettings settings;

 private:
  struct Scratch {
    std::vector<BodyMotion> bodies;
    std::vector<BodyRow> rows;
    std::vector<int> contact_rows;  // per contact of the world: its first row (then the rows' end)
  };
  void step_world(int w, const StepInput& step, int thread) override;
  void check_settings() const override { settings.check(); }
  int thread_count() const override { return settings.num_threads; }
  GuardSettings guard_settings() const override {
    return {settings.on_divergence, settings.divergence_speed, settings.divergence_depth};
  }
  // the rows of world w's constraints (each axis locked, limited or driven) and contacts
  void constraint_rows(int w, const StepInput& step, Scalar share, Scratch& s);
  void contact_rows(int w, const StepInput& step, Scratch& s) const;
  // the row's inverse inertias and effective mass (the bodies' and cfm), and its starting impulse (applied once all
  // rows are made)
  void finish_row(BodyRow& row, Scratch& s, Scalar start) const;
  // settings.position_iterations passes moving world w's bodies back where their rigid joints allow (positions only)
  void hold_joints(int w, Scratch& s) const;
  // the sweeps; returns whether they converged
  bool sweep(Scratch& s) const;

  std::vector<Scratch> scratch_;         // per thread
  std::vector<Scalar> kept_;             // per constraint: 3 per axis (locked or lower limit, upper limit, spring)
  std::vector<std::uint8_t> converged_;  // per world: whether its last sweeps converged
};

}  // namespace novaphy
