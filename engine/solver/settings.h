// The settings of the solvers, one field table each (SolverFeatherstone, SolverSemiImplicit, SolverXPBD): each line
// gives a setting's type, name, default, the range step() accepts, its unit and what it does. A table declares the
// struct, checks it (check()), binds it to Python (bindings/solver_*.cpp, hence the type stub) and writes the
// reference table (docs/settings.md, by tools/make_settings_doc.py); adding a setting is adding a line. A setting of
// one meaning has one name in every table.
#pragma once

#include <cstdint>
#include <limits>

#include "kernels/spatial.h"

namespace novaphy {

// what step does with an articulation whose state went non-finite or too fast
enum class DivergencePolicy : int { Raise = 0, Flag = 1, Reset = 2 };

inline constexpr Scalar kUnbounded = std::numeric_limits<Scalar>::infinity();
inline constexpr int kIntUnbounded = std::numeric_limits<int>::max();

// X(type, name, default, lowest, highest, unit, doc); a bool or an enum has no range (0, 0)
#define NOVAPHY_SOLVER_SETTINGS(X)                                                                                    \
  X(int, num_iterations, 20, 0, kIntUnbounded, "", "PGS sweeps per step, at most.")                                   \
  X(Scalar, pgs_tolerance, 3e-5, 0, 1e6, "m/s, rad/s",                                                                \
    "Stop the PGS sweeps of a world once one sweep changed no row's velocity by more than this; 0: once one sweep "   \
    "changed no impulse at all (a fixed point).")                                                                     \
  X(Scalar, linear_slop, 0.001, 0, 1e3, "m", "Penetration the position correction leaves alone.")                     \
  X(Scalar, erp, 0.2, 0, 1, "", "Share of the penetration beyond the slop removed per step.")                         \
  X(Scalar, cfm, 1e-6, 0, 1e6, "", "Constraint force mixing: softens every constraint row.")                          \
  X(Scalar, warmstarting_factor, 0.85, 0, 1, "",                                                                      \
    "Share of the last step's impulses a world's limit, dry-friction and equality rows start from where its last "    \
    "sweeps ran out (num_iterations) before converging to pgs_tolerance; where they converged, all of them. A "       \
    "contact's rows always start from all of theirs.")                                                                \
  X(Scalar, restitution_threshold, 0.2, 0, 1e6, "m/s", "Approach speed below which contacts do not bounce.")          \
  X(bool, use_warmstarting, true, 0, 0, "", "Rows start from a share of the last step's impulses.")                   \
  X(bool, soft_constraints, true, 0, 0, "",                                                                           \
    "Rows of joint and tendon limits, dry friction and equality constraints whose solref is not (0, 0) (an imported " \
    "model's: MuJoCo's) are soft as MuJoCo's; off: every one of them a hard row (erp, linear_slop). Contacts keep "   \
    "their shapes' softness.")                                                                                        \
  X(Scalar, angular_damping, 0.05, 0, kUnbounded, "1/s",                                                              \
    "Rotational dof velocities are scaled by (1 - angular_damping dt) each step.")                                    \
  X(int, update_mass_matrix_interval, 1, 1, kIntUnbounded, "", "Recompute and refactor H every N steps.")             \
  X(int, max_condim, 6, 3, 6, "",                                                                                     \
    "The most friction a contact gets of its shapes' condim: 6 MuJoCo's all (torsional and rolling rows for condim "  \
    "4 and 6), 4 no rolling rows, 3 neither; fewer rows, a faster step (docs/step.md, Condim).")                      \
  X(Scalar, friction_smoothing, 1.0, 0, 1, "",                                                                        \
    "0: box friction per tangent (the direction snaps to the tangent axes); 1: circular cone (friction opposes the "  \
    "slip smoothly; with condim 4 or 6 in the model, MuJoCo's elliptic cone over each contact's friction rows, "      \
    "docs/step.md); between: a blend.")                                                                               \
  X(bool, use_tile_gemm, false, 0, 0, "", "H as the tiled product sum J_i^T I_i J_i instead of CRBA.")                \
  X(bool, fuse_cholesky, true, 0, 0, "", "Factor H and forward-substitute in one pass.")                              \
  X(int, aba_min_dofs, 32, 0, kIntUnbounded, "",                                                                      \
    "Articulations of at least this many dofs take the dense route with ABA's O(n) factor and solves (refactored "    \
    "every step) instead of CRBA and the LTL factor.")                                                                \
  X(Scalar, coriolis_implicitness, 0, 0, 1, "",                                                                       \
    "0: explicit Coriolis forces; 0.5: linearised midpoint (energy kept to second order); 1: linearised backward "    \
    "Euler. Above 0 every articulation takes the dense route with an LU of M + theta dt C each step, O(n^3).")        \
  X(int, num_threads, 0, 0, kIntUnbounded, "",                                                                        \
    "OpenMP threads (0: all available); results are bit-identical for any count.")                                    \
  X(bool, profile_stages, false, 0, 0, "",                                                                            \
    "Accumulate each stage's wall time into stage_seconds: each pass's wall time shared out as the threads' time "    \
    "went to the stages of its units (the same schedule and arithmetic as unprofiled, a few clock reads a unit "      \
    "more).")                                                                                                         \
  X(bool, count_serial_time, false, 0, 0, "",                                                                         \
    "Accumulate each step's wall time and that of its parallel work into serial_seconds (its serial share: the "      \
    "rest over the whole).")                                                                                          \
  X(bool, weld_fixed_joints, true, 0, 0, "",                                                                          \
    "Merge bodies held by Fixed joints into their parent's link, so they cost nothing in the dynamics (read when "    \
    "the solver is made).")                                                                                           \
  X(bool, use_batch_kernels, true, 0, 0, "",                                                                          \
    "Step articulations that share joints, frames and axes (replicated worlds) a SIMD block of worlds at a time in "  \
    "the model's precision; off: every articulation takes the dense route.")                                          \
  X(DivergencePolicy, on_divergence, DivergencePolicy::Flag, 0, 0, "",                                                \
    "What step does with an articulation that diverged (its state went non-finite, too fast or too energetic, or a "  \
    "contact too deep): Raise (nothing written), Flag (it keeps its previous state; diverged() marks it) or Reset "   \
    "(it restarts from the reset state: set_reset_state or set_reset_keyframe, else joint_q0 at rest; its world is "  \
    "marked in the output's world_reset, so its next collide and step use none of its past, and its sensors read "    \
    "0).")                                                                                                            \
  X(Scalar, divergence_speed, 1e6, 0, kUnbounded, "m/s, rad/s", "A dof speed beyond which an articulation diverged.") \
  X(Scalar, divergence_energy, 1e7, 0, kUnbounded, "J/kg",                                                            \
    "A kinetic energy per kilogram of its mass beyond which an articulation diverged after its step (its energy "     \
    "blew up): 1/2 sum_k H_kk qd_k^2 over its mass, H_kk the diagonal of its mass matrix at joint_q0 (1e7 J/kg: "     \
    "about 4500 m/s).")                                                                                               \
  X(Scalar, divergence_depth, 0.5, 0, kUnbounded, "m",                                                                \
    "A contact deeper than this among those a step is given (found at its input state, where the last step left "     \
    "the bodies) marks the articulations it touches diverged: a step too large for the scene took them through a "    \
    "surface.")                                                                                                       \
  X(std::int64_t, stream_body_output_above, std::int64_t{2} << 20, 0, std::numeric_limits<std::int64_t>::max(),       \
    "bytes",                                                                                                          \
    "The blocks write body_q and body_qd around the caches (non-temporal stores) when the step's data, the state's "  \
    "arrays and the solver's, exceed this (0: always); tools/stream_threshold.py finds a machine's.")

// the settings both maximal-coordinate solvers read alike: threads over the worlds and the divergence guard
#define NOVAPHY_MAXIMAL_STEP_SETTINGS(X)                                                                             \
  X(int, num_threads, 0, 0, kIntUnbounded, "",                                                                       \
    "OpenMP threads (0: all available) over the worlds; results are bit-identical for any count.")                   \
  X(DivergencePolicy, on_divergence, DivergencePolicy::Flag, 0, 0, "",                                               \
    "What step does with a world that diverged (a body's state went non-finite or too fast, or a contact too "       \
    "deep): Raise (nothing written), Flag (it keeps its previous state; diverged() marks it) or Reset (it restarts " \
    "from joint_q0 at rest, marked in the output's world_reset).")                                                   \
  X(Scalar, divergence_speed, 1e6, 0, kUnbounded, "m/s, rad/s", "A body speed beyond which its world diverged.")     \
  X(Scalar, divergence_depth, 0.5, 0, kUnbounded, "m",                                                               \
    "A contact deeper than this among those a step is given marks its world diverged.")

// SolverSemiImplicit (engine/solver/semi_implicit/solver_semi_implicit.h)
#define NOVAPHY_SEMI_IMPLICIT_SETTINGS(X)                                                                              \
  X(int, num_iterations, 20, 0, kIntUnbounded, "", "PGS sweeps per step over every row of a world, at most.")          \
  X(int, position_iterations, 0, 0, kIntUnbounded, "",                                                                 \
    "Passes after integrating that move the bodies back where their rigid joints allow (nonlinear Gauss-Seidel with "  \
    "XPBD's corrections; the velocities are left alone): less of the drift the rows' erp leaves at speed, at some "    \
    "of the motion's accuracy (docs/solvers.md); 0: none.")                                                            \
  X(Scalar, pgs_tolerance, 1e-6, 0, 1e6, "m/s, rad/s",                                                                 \
    "Stop the sweeps of a world once one sweep changed no row's velocity by more than this.")                          \
  X(Scalar, linear_slop, 0.001, 0, 1e3, "m", "Penetration the position correction leaves alone.")                      \
  X(Scalar, erp, 0.2, 0, 1, "",                                                                                        \
    "Share of a rigid constraint's error (a penetration beyond the slop, a joint's drift) removed per step.")          \
  X(Scalar, cfm, 1e-8, 0, 1e6, "", "Constraint force mixing: softens every constraint row.")                           \
  X(Scalar, warmstarting_factor, 0.85, 0, 1, "",                                                                       \
    "Share of the last step's impulses a world's joint and limit rows start from where its sweeps ran out before "     \
    "converging; where they converged, all of them. A contact's rows always start from all of theirs.")                \
  X(Scalar, restitution_threshold, 0.2, 0, 1e6, "m/s", "Approach speed below which contacts do not bounce.")           \
  X(bool, use_warmstarting, true, 0, 0, "", "Rows start from a share of the last step's impulses.")                    \
  X(Scalar, angular_damping, 0.05, 0, kUnbounded, "1/s",                                                               \
    "Each body's angular velocity is scaled by (1 - angular_damping dt) each step.")                                   \
  X(int, max_condim, 6, 3, 6, "", "The most friction a contact gets of its shapes' condim (as SolverFeatherstone's).") \
  X(Scalar, friction_smoothing, 1.0, 0, 1, "",                                                                         \
    "0: box friction per tangent; 1: circular cone (condim 4, 6: elliptic over the friction rows); between: a blend.") \
  NOVAPHY_MAXIMAL_STEP_SETTINGS(X)

// SolverXPBD (engine/solver/xpbd/solver_xpbd.h); names as Newton's SolverXPBD's where the meaning is the same
#define NOVAPHY_XPBD_SETTINGS(X)                                                                                   \
  X(int, iterations, 2, 1, kIntUnbounded, "", "Constraint passes per substep.")                                    \
  X(int, substeps, 8, 1, kIntUnbounded, "", "Substeps per step (each of dt / substeps).")                          \
  X(Scalar, joint_linear_relaxation, 1.0, 0, 2, "", "Share of a joint's positional correction applied per pass.")  \
  X(Scalar, joint_angular_relaxation, 1.0, 0, 2, "", "Share of a joint's rotational correction applied per pass.") \
  X(Scalar, joint_linear_compliance, 0, 0, kUnbounded, "m/N",                                                      \
    "Compliance added to every joint's positional constraints (a joint's own: model.joint_compliance).")           \
  X(Scalar, joint_angular_compliance, 0, 0, kUnbounded, "rad/(N m)",                                               \
    "Compliance added to every joint's rotational constraints.")                                                   \
  X(Scalar, rigid_contact_relaxation, 1.0, 0, 2, "", "Share of a contact's correction applied per pass.")          \
  X(Scalar, max_depenetration_velocity, 1.0, 0, kUnbounded, "m/s",                                                 \
    "A penetration a step starts with is pushed out no faster than this (PhysX's name): corrected at once, a "     \
    "keyframe's feet sunk into the floor would leave at penetration / substep.")                                   \
  X(Scalar, angular_damping, 0.0, 0, kUnbounded, "1/s",                                                            \
    "Each body's angular velocity is scaled by (1 - angular_damping h) each substep h.")                           \
  X(bool, enable_restitution, false, 0, 0, "", "Contacts bounce by their shapes' restitution.")                    \
  NOVAPHY_MAXIMAL_STEP_SETTINGS(X)

struct SolverFeatherstoneSettings {
#define NOVAPHY_DECLARE_SETTING(type, name, value, lowest, highest, unit, doc) type name = value;
  NOVAPHY_SOLVER_SETTINGS(NOVAPHY_DECLARE_SETTING)
#undef NOVAPHY_DECLARE_SETTING

  // throws Error naming the first setting out of its range
  void check() const;
};

struct SolverSemiImplicitSettings {
#define NOVAPHY_DECLARE_SETTING(type, name, value, lowest, highest, unit, doc) type name = value;
  NOVAPHY_SEMI_IMPLICIT_SETTINGS(NOVAPHY_DECLARE_SETTING)
#undef NOVAPHY_DECLARE_SETTING
  void check() const;
};

struct SolverXPBDSettings {
#define NOVAPHY_DECLARE_SETTING(type, name, value, lowest, highest, unit, doc) type name = value;
  NOVAPHY_XPBD_SETTINGS(NOVAPHY_DECLARE_SETTING)
#undef NOVAPHY_DECLARE_SETTING
  void check() const;
};

}  // namespace novaphy
