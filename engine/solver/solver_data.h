// What a step of SolverFeatherstone writes and keeps for the next (as MuJoCo's mjData beside mjModel): its vectors
// as one field table. What is built once for the model: SolverModel (engine/solver/solver_model.h).
#pragma once

#include <cstdint>
#include <vector>

#include "kernels/spatial.h"

namespace novaphy {

// the solver's step vectors as one field table, X(type, name, count, doc), `count` an expression over the
// SolverCounts n: the table sizes them (and again as a step's contacts outgrow them) and counts their bytes
struct SolverCounts {
  int dofs = 0, coords = 0, articulations = 0, limit_cells = 0, contacts = 0;
  int tendons = 0, equalities = 0;
};
#define NOVAPHY_SOLVER_DATA(X)                                                                                      \
  X(Scalar, qd, n.dofs, "velocity being solved, between the passes of a step")                                      \
  X(Scalar, q_next, n.coords, "coordinates after the step, between the passes")                                     \
  X(Scalar, tau, n.dofs, "the control's joint forces with its actuators'")                                          \
  X(Scalar, actuator_stiffness, n.dofs, "the actuators' stiffness on each dof, taken implicitly")                   \
  X(Scalar, actuator_damping, n.dofs, "the actuators' damping on each dof, taken implicitly")                       \
  X(Scalar, tendon_force, n.tendons, "the force along each tendon: its spring's, damper's and actuators'")          \
  X(Scalar, limit_impulse, n.limit_cells, "the last step's limit impulses, the warm starts of limit rows")          \
  X(Scalar, friction_impulse, n.dofs, "the last step's friction-loss impulses, the warm starts of their rows")      \
  X(Scalar, equality_impulse, 6 * n.equalities, "the last step's equality impulses, the warm starts of their rows") \
  X(Scalar, tendon_impulse, 3 * n.tendons,                                                                          \
    "the last step's tendon-limit and dry-friction impulses, their rows' warm starts")                              \
  X(std::uint8_t, pgs_converged, n.articulations, "1 where the last sweeps over its rows stopped at the tolerance") \
  X(std::uint8_t, diverged, n.articulations, "1 where the last step's divergence guard fired")                      \
  X(std::uint8_t, flagged, n.articulations, "1 where an input or a contact too deep diverged it before its step")   \
  X(int, factor_failure, n.articulations, "the dof whose pivot failed this step, else -1")                          \
  X(std::uint8_t, touched, n.articulations, "1 where a contact joins it to another moving articulation this step")  \
  X(int, contact_start, n.articulations + 1, "where each articulation's contacts start in contact_list")            \
  X(int, contact_list, n.contacts, "the contacts each articulation's unit solves, by articulation")                 \
  X(int, contact_owner, n.contacts, "the articulation whose unit solves the contact, else -1 (the islands)")        \
  X(int, fill, n.articulations + 1, "scratch of the counting sorts")

struct SolverData {
#define NOVAPHY_DECLARE_DATA(type, name, count, doc) std::vector<type> name;
  NOVAPHY_SOLVER_DATA(NOVAPHY_DECLARE_DATA)
#undef NOVAPHY_DECLARE_DATA
  // grows each field to its count (a field's entries are kept)
  void allocate(const SolverCounts& n) {
#define NOVAPHY_ALLOCATE_DATA(type, name, count, doc) \
  if (name.size() < static_cast<size_t>(count)) name.resize(static_cast<size_t>(count), type{});
    NOVAPHY_SOLVER_DATA(NOVAPHY_ALLOCATE_DATA)
#undef NOVAPHY_ALLOCATE_DATA
  }
  std::size_t bytes() const {
    std::size_t n = 0;
#define NOVAPHY_DATA_BYTES(type, name, count, doc) n += name.size() * sizeof(type);
    NOVAPHY_SOLVER_DATA(NOVAPHY_DATA_BYTES)
#undef NOVAPHY_DATA_BYTES
    return n;
  }
};

}  // namespace novaphy
