// SolverFeatherstone: one time step of every articulation in reduced coordinates.
//   forward kinematics -> RNEA bias forces -> CRBA mass matrix (+ implicit damping, springs and PD
//   drives) -> Cholesky -> unconstrained velocity -> sequential-impulse PGS over contact and
//   joint-limit rows through M^-1 J^T -> semi-implicit integration -> forward kinematics
#pragma once

#include <omp.h>

#include <Eigen/LU>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/articulation_batches.h"
#include "engine/collision.h"
#include "engine/weld.h"
#include "kernels/pgs.h"

namespace novaphy {

// what step does with an articulation whose state went non-finite or too fast
enum class DivergencePolicy : int { Raise = 0, Flag = 1, Reset = 2 };

struct SolverFeatherstoneSettings {
  int num_iterations = 20;  // PGS sweeps, at most
  // the sweeps stop once one sweep changed no row's own velocity by more than this (m/s, rad/s),
  // per world (a world's result does not depend on its block-mates); 0: once one sweep changed no
  // impulse at all (a fixed point, which the sweeps left would repeat bit for bit)
  Scalar pgs_tolerance = 0;
  Scalar linear_slop = 0.001;          // penetration (m) left alone by the position correction
  Scalar erp = 0.2;                    // fraction of the penetration beyond the slop removed per step
  Scalar cfm = 1e-6;                   // constraint force mixing: softens every row
  Scalar warmstarting_factor = 0.85;   // share of the previous step's impulses applied up front
  Scalar restitution_threshold = 0.2;  // approach speed (m/s) below which contacts do not bounce
  bool use_warmstarting = true;
  Scalar angular_damping = 0.05;        // rotational dof velocities scaled by (1 - angular_damping dt)
  int update_mass_matrix_interval = 1;  // recompute and refactor H every N steps
  Scalar friction_smoothing = 1.0;      // 0: box friction per tangent; 1: circular cone; between: blend
  // H as sum J_i^T I_i J_i over link Jacobians instead of CRBA (batched: multiplied in register tiles,
  // kernels/batch.h batch_mass_matrix_gemm)
  bool use_tile_gemm = false;
  bool fuse_cholesky = true;  // factor and forward-substitute in one pass
  // articulations with at least this many dofs use ABA's O(n) factor and solves instead of CRBA +
  // Cholesky (O(n^2) + O(n^3)); they refactor every step, whatever update_mass_matrix_interval says
  // (32: where a chain steps faster on ABA, bench/chain_bench.cpp; branched trees of fewer dofs favour CRBA)
  int aba_min_dofs = 32;
  // how implicitly the Coriolis and centrifugal forces are integrated: 0 explicit (semi-implicit
  // Euler); 0.5 the linearised midpoint rule (energy kept to second order, no blow-up on fast spins
  // or whipping chains); 1 linearised backward Euler (damps). Above 0 every articulation takes the
  // dense path (CRBA, d bias/d qd by 2n RNEAs, an LU of M + theta dt C each step): O(n^3)
  Scalar coriolis_implicitness = 0;
  int num_threads = 0;  // OpenMP threads over articulations; 0: all available
  // accumulate each stage's wall time into stage_seconds(); the batched blocks then run each stage
  // over all blocks in turn rather than a block's whole step at a time (the same arithmetic)
  bool profile_stages = false;
  // bodies held to a parent body by a Fixed joint are merged into the parent's link, so they cost
  // nothing in the dynamics (read when the solver is made)
  bool weld_fixed_joints = true;
  // articulations that share joints, frames and axes (replicated worlds) are stepped a SIMD block of
  // worlds at a time by the batched kernels, in the model's precision (engine/articulation_batches.h);
  // off, or while coriolis_implicitness > 0, every articulation takes the scalar kernels
  bool use_batch_kernels = true;
  // Flag: the articulation keeps its previous state and solver.diverged() marks it; Reset: it restarts
  // from the model's joint_q0 at rest; Raise: step throws and writes nothing
  DivergencePolicy on_divergence = DivergencePolicy::Flag;
  Scalar divergence_speed = 1e6;  // |qd| beyond this (m/s, rad/s) counts as diverged
  // the batched blocks write body_q and body_qd around the caches (non-temporal stores, which do not
  // read in the lines they overwrite) when the step's data, the state's arrays and the solver's, exceed
  // this many bytes; below it the output stays in cache for whatever reads it next (0: always). The
  // default is where streaming started to pay on a Sapphire Rapids guest (2 MB of L2 a core): streamed
  // against stored, 512 and 1024 quadrupeds (2.4 and 4.7 MB) 1.03-1.05x and 1.08-1.19x, 256 humanoid.xml
  // robots (2.2 MB) 0.98-1.10x, 64 quadrupeds (0.3 MB) 0.95-0.99x. Not on every machine: on a Zen 5
  // guest (1 MiB L2 a core, 32 MiB L3) streaming paid only past the L3 (float32 quadrupeds: 2.7-28 MB
  // 0.87-0.93x, 37.5 MB 0.98x, 74.6 MB 1.20x; tools/stream_threshold.py measures it)
  std::int64_t stream_body_output_above = std::int64_t{2} << 20;

  // throws Error naming the first setting out of range
  void check() const;
};

// wall time of each stage of step, accumulated while settings.profile_stages is on
struct SolverStageSeconds {
  double dynamics = 0;      // FK, RNEA, mass matrix and its factor, unconstrained velocity
  double limit_rows = 0;    // joint-limit rows and their Jacobians
  double contact_rows = 0;  // contact rows, their Jacobians and targets
  double solve = 0;         // per island of articulations joined by rows: M^-1 J^T, warm start, PGS sweeps
  double integrate = 0;     // divergence guard, joint integration, FK into body_q/body_qd
  int steps = 0;
};

struct JointSupportMatrix {
  struct Entry {
    std::string joint;
    bool supported;
  };
  std::vector<Entry> entries;
  bool supports(const std::string& joint) const;  // throws Error for an unknown name
  std::string to_string() const;
};

// keeps a reference to the model, which must outlive it
class SolverFeatherstone {
 public:
  explicit SolverFeatherstone(const Model& model, const SolverFeatherstoneSettings& settings = {});

  // state_in may be state_out; on error nothing is written, with one exception: under on_divergence Flag
  // or Reset the batched blocks write each world's new state as they step it, so a mass matrix that is not
  // positive definite in some world (a massless leaf link, which no builder call makes) raises after the
  // other worlds' states were written; that world's is left as it was
  void step(const State& state_in, State& state_out, const Control& control, Contacts& contacts, Scalar dt);

  JointSupportMatrix joint_support() const;
  // per articulation: 1 where the last step's divergence guard fired
  const std::vector<std::uint8_t>& diverged() const { return diverged_; }
  const Model& model() const { return model_; }
  const SolverStageSeconds& stage_seconds() const { return stage_seconds_; }
  void reset_stage_seconds() { stage_seconds_ = {}; }
  // bytes the solver holds for its articulations: batched blocks, scalar scratch, step vectors
  std::size_t memory_bytes() const;
  // the batches the articulations were grouped into (nullptr when none is batched)
  const ArticulationBatches* batches() const { return batches_.get(); }

  SolverFeatherstoneSettings settings;

 private:
  // throws Error naming the first bad argument; notes whether in.body_f has a nonzero wrench
  void check_step(const State& in, const State& out, const Control& control, const Contacts& contacts, Scalar dt);
  // qd_ = the velocity before constraints, H factored (when `refactor`) or its factor reused
  void unconstrained_velocity(const State& in, const Control& control, Scalar dt, bool refactor);
  ArticulationBatches::DynamicsOptions dynamics_options(bool refactor, Scalar dt) const;
  // the blocks' divergence guard: settings.divergence_speed, into diverged_
  ArticulationBatches::Divergence divergence();
  // the blocks of this (fused) step write their worlds' new states to out as they step them: not under
  // Raise, whose divergence error writes nothing (integrate stores them after the guard)
  bool stores_in_step() const;
  // the blocks write body_q and body_qd around the caches (settings.stream_body_output_above)
  bool stream_body_output() const;
  // the control's joint forces with the actuators' added (rhs_, or joint_f itself when nothing adds)
  const Scalar* control_forces(const Control& control);
  // throws naming the first articulation whose factor failed this step
  void check_factors() const;
  // what angular damping leaves of a rotational dof's velocity over dt
  Scalar angular_keep(Scalar dt) const { return std::max<Scalar>(0, 1 - settings.angular_damping * dt); }
  void build_contact_rows(const Contacts& contacts, Scalar dt);
  void build_limit_rows(const State& in, Scalar dt);
  void group_islands();
  void solve_islands();
  // the sweeps' settings, for the scalar islands and the blocks alike
  PgsSettings pgs_settings() const;
  void solve_constraints(Contacts& contacts);
  void integrate(const State& in, State& out, Scalar dt);
  template <typename F>
  void for_each_articulation(F&& f);
  int thread_count() const { return settings.num_threads > 0 ? settings.num_threads : omp_get_max_threads(); }
  // true when articulation a is stepped by the batched kernels this step
  bool on_batch(int a) const { return batch_step_ && batches_->active(a); }
  // the articulation body moves with, -1 for the world or a body of an articulation without dofs
  int moving_articulation(int body) const;
  // touched_ and the contacts each block solves (block_contact_start_, block_contacts_, contact_*_)
  void list_block_contacts(const Contacts& contacts);
  // articulation a's scalar scratch, sized on first use
  ArticulationScratch& scratch(int a);

  // a row over the dofs of up to two articulations (-1: none), J zeroed; finish_row computes
  // M^-1 J^T and the effective mass once J is filled in (solve_constraints, per island)
  int begin_row(int art_a, int art_b, RowKind kind, Scalar target);
  Scalar* row_jacobian(int row, int art);
  void finish_row(int row);
  // a contact-type row: relative velocity of body b's point p minus body a's along d (-1: the world)
  int add_row(int body_a, int body_b, const Vec3& p, const Vec3& d, RowKind kind, Scalar target);
  void add_point_jacobian(int body, const Vec3& p, const Vec3& d, Scalar sign, Scalar* J) const;
  // x = M^-1 x for articulation a, with the factor of the last step (Cholesky or ABA)
  void solve_mass(int a, Scalar* x);

  // body_q and body_qd of articulation a's bodies, welded ones included, from its scratch
  void store_bodies(int a, State& out) const;
  // applied wrenches of articulation a's bodies gathered onto its links (welded bodies' onto theirs)
  const Scalar* link_wrenches(int a, const Scalar* body_f);

  const Model& model_;
  WeldedModel welded_;                         // what the kernels see: art_ views its arrays
  std::vector<std::vector<int>> welded_into_;  // per articulation: its welded bodies
  std::vector<Scalar> link_f_;                 // [body][6] link_wrenches' output
  std::vector<ArticulationView> art_;
  std::vector<ArticulationScratch> scratch_;
  std::unique_ptr<ArticulationBatches> batches_;
  bool batch_step_ = false;
  bool all_on_batch_ = false;          // this step: every articulation with dofs in a block that is on
  bool fused_step_ = false;            // this step: the blocks step a block at a time (ArticulationBatches::step)
  std::vector<int> unbatched_;         // articulations without dofs (no block has them)
  std::int64_t step_bytes_ = 0;        // what a step touches: the solver's memory when made and the state's arrays
  bool wrenches_ = false;              // the step's input has a nonzero body_f
  bool drives_ = false;                // the step's control has a nonzero PD gain
  std::vector<std::uint8_t> touched_;  // per articulation: 1 where a contact joins it to another moving one
  // this step's rows on the scalar path: the articulations whose limits it builds (their blocks solve the
  // others' limit and contact rows; no contact joins those to another moving articulation), the contacts
  // it solves
  std::vector<int> scalar_rows_, scalar_contacts_;
  // list_block_contacts' output: per contact its articulation when its block solves it (else -1), the
  // links of its bodies there, its friction and restitution; per articulation its contacts
  std::vector<int> contact_block_, contact_link_a_, contact_link_b_;
  std::vector<Scalar> contact_mu_, contact_restitution_;
  std::vector<int> block_contact_start_, block_contacts_;
  std::vector<int> fill_;  // scratch of the groupings by key (actuators by dof, contacts by block, rows by island)
  std::vector<int> body_articulation_, body_link_;
  std::vector<int> dof_articulation_;
  // per dof: the actuators that drive it, in order, dof_actuators_[dof_actuator_start_[d] .. [d + 1])
  std::vector<int> dof_actuator_start_, dof_actuators_;
  std::vector<int> rotational_dof_;  // dofs scaled by angular damping
  VecX qd_;                          // velocity being solved, all dofs
  const Scalar* qd_in_ = nullptr;    // the step's initial velocity, in.joint_qd (read before out is written)
  VecX q_next_;
  VecX rhs_;
  VecX zero_;
  int steps_since_factor_ = 0;
  bool factor_kept_ = false;  // the last step's factor kept for this one (its update_mass_matrix_interval > 1)
  Scalar factored_dt_ = 0;
  // constraint rows and their pools
  std::vector<PgsRow> rows_;
  int row_count_ = 0;
  // islands (articulations joined by rows, named by their lowest articulation): rows of island i are
  // island_rows_[island_start_[i] .. island_start_[i + 1])
  std::vector<int> island_parent_, island_of_row_, island_start_, island_rows_;
  std::vector<Scalar> J_, MinvJT_;
  int pool_size_ = 0;
  std::vector<std::uint8_t> diverged_;
  std::vector<int> factor_failure_;                     // per articulation: first dof whose factor failed, -1
  std::vector<std::uint8_t> factored_aba_;              // per articulation: 1 where the factor is ABA's, 0 Cholesky's
  std::vector<std::uint8_t> factored_batch_;            // per articulation: 1 where the last factor is a batch's
  std::vector<Eigen::PartialPivLU<MatX>> implicit_lu_;  // per articulation: M + theta dt C (coriolis_implicitness)
  std::vector<VecX> factored_diag_;                     // per articulation: the implicit diagonal in s.H's factor
  std::vector<std::uint8_t> constant_mass_;             // per articulation: 1 for Prismatic and Fixed joints only
  std::vector<MatX> constant_H_;                        // per articulation: its H once computed, where constant
  std::vector<int> contact_row_;                        // first row of each of scalar_contacts_
  // Revolute and Prismatic joints with a finite limit, by articulation: a's are from limited_start_[a]
  std::vector<int> limited_joints_, limited_start_;
  std::vector<int> limit_row_;  // [dof][2] row of each active limit, -1
  // the impulses of the previous step's limit rows: limited joint m's lower (side 0) and upper (1) at
  // limit_impulse_[limit_cell_[2 * m + side]] (the batches lay out their articulations' cells)
  std::vector<Scalar> limit_impulse_;
  std::vector<int> limit_cell_;
  SolverStageSeconds stage_seconds_;
};

}  // namespace novaphy
