// SolverFeatherstone: one time step of every articulation in reduced coordinates.
//   forward kinematics -> RNEA bias forces -> CRBA mass matrix (+ implicit damping, springs and PD
//   drives) -> its factor -> unconstrained velocity -> sequential-impulse PGS over contact and
//   joint-limit rows through M^-1 J^T -> semi-implicit integration -> forward kinematics
// Every articulation goes through the same stages (engine/solver/route.h), on one of two routes chosen
// when the solver is made (and again when a setting that decides them changes): SIMD blocks of worlds
// (engine/solver/blocks/blocks.h) or one articulation on the scalar kernels (engine/solver/dense/dense.h);
// rows that join articulations are solved as islands (engine/solver/islands/rows.h). docs/step.md tells the step.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/actuator.h"
#include "engine/model/weld.h"
#include "engine/solver/blocks/blocks.h"
#include "engine/solver/dense/dense.h"
#include "engine/solver/islands/rows.h"
#include "engine/solver/parts/rows.h"
#include "engine/solver/settings.h"
#include "engine/threads/exclusive_call.h"
#include "engine/threads/parallel.h"

namespace novaphy {

// wall time of each stage of step, accumulated while settings.profile_stages is on
struct SolverStageSeconds {
  double dynamics = 0;      // FK, RNEA, mass matrix and its factor, unconstrained velocity
  double limit_rows = 0;    // joint-limit rows and their Jacobians
  double contact_rows = 0;  // contact rows, their Jacobians and targets
  double solve = 0;         // M^-1 J^T, warm start and PGS sweeps
  double integrate = 0;     // joint integration, the divergence guard, FK into body_q/body_qd
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
  X(Scalar, tendon_impulse, 2 * n.tendons, "the last step's tendon-limit impulses, the warm starts of their rows")  \
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
  void allocate(const SolverCounts& n);  // grows each field to its count (a field's entries are kept)
  std::size_t bytes() const;
};

// keeps a reference to the model, which must outlive it and is read-only after finalize: the solver reads most of
// its parameters once, when made, so a later edit of the model is not a supported way to change them
class SolverFeatherstone {
 public:
  explicit SolverFeatherstone(const Model& model, const SolverFeatherstoneSettings& settings = {});

  // state_in may be state_out; on error nothing is written, with one exception: under on_divergence Flag
  // or Reset each world's new state is written as its unit steps it, so a non-finite input (joint_q, joint_qd,
  // body_f, the control: found from the world's output) or a mass matrix that is not positive definite in some
  // world (a massless leaf link, which no builder call makes) raises after the other worlds' states were
  // written; that world is left as it was. A negative PD gain in the control raises likewise. One step at a time:
  // a step called while another thread's step of this solver runs throws Error (one solver per thread)
  void step(const State& state_in, State& state_out, const Control& control, Contacts& contacts, Scalar dt);

  // the state an articulation restarts from under on_divergence Reset: its joint_q and joint_qd (copied; by
  // default the model's joint_q0 when the solver was made, at rest); throws Error where it is not the model's or
  // not finite
  void set_reset_state(const State& state);
  // the reset state at the model's keyframe of that name (its coordinates and velocities)
  void set_reset_keyframe(const std::string& keyframe) { set_reset_state(model_.state(keyframe)); }

  JointSupportMatrix joint_support() const;
  // per articulation: 1 where the last step's divergence guard fired
  const std::vector<std::uint8_t>& diverged() const { return data_.diverged; }
  const Model& model() const { return model_; }
  const SolverStageSeconds& stage_seconds() const { return stage_seconds_; }
  void reset_stage_seconds() { stage_seconds_ = {}; }
  // wall time of whole steps and of their parallel work (the passes over blocks and dense articulations, each
  // unit's stages on its thread; the islands' solve; the contact lists' regions when they take more than one
  // thread), accumulated while settings.count_serial_time is on; the rest of a step (argument checks, the guard,
  // the counting sort of unordered contacts) is the share more threads do not shorten
  const SerialSeconds& serial_seconds() const { return serial_seconds_; }
  void reset_serial_seconds() { serial_seconds_ = {}; }
  // bytes the solver holds for its articulations: blocks, scalar scratch, rows, step vectors
  std::size_t memory_bytes() const;
  // the batches the articulations were grouped into (nullptr when none is batched)
  const ArticulationBatches* batches() const { return batches_.get(); }

  SolverFeatherstoneSettings settings;

 private:
  // throws Error naming the first bad argument but a non-finite input an articulation reads, which its step finds
  // from its outputs (guard, check_factors), and checks the entries no articulation reads (loose_*)
  void check_step(const State& in, const State& out, const Control& control, const Contacts& contacts, Scalar dt);
  // per articulation what its step reads beside its coordinates and dofs: its bodies (body_f), actuators, tendons
  void index_inputs();
  // notes in `local` whether these articulations have wrenches (a nonzero body_f) and drives (a nonzero PD gain),
  // and returns whether body_f, the gains or actuator_ctrl hold an entry not finite or a gain below 0 (an infinite
  // command would be clamped to its control range: no output shows it); with `valid`, whether all they read is
  // finite and their gains not negative: their joint_q, joint_qd, body_f, actuator_ctrl and per-dof control (the
  // PD targets where a gain is nonzero). Any other non-finite input reaches the step's output (a drive's gain or a
  // wrench that is not finite is nonzero), so the pass scans only body_f, the gains and the commands; the guard and
  // check_factors scan all of an articulation whose step went wrong
  bool scan_unit(const int* arts, int count, StepContext& local, bool* valid) const;
  // scan_unit's notes of block units [begin, end), scanned back to back (each input array read as one stream, as
  // a pass over all of them would read it, rather than a short run a unit between the unit's other work)
  struct UnitNotes {
    static constexpr int kUnits = 8;
    int begin = 0, end = 0;
    std::array<std::uint8_t, kUnits> drives, wrenches, invalid;
  };
  // local's notes for block unit u of a thread's run that ends at `run_end`, from `notes` or scanned into it
  // with the units after u; returns scan_unit's
  bool block_unit_notes(int u, int run_end, UnitNotes& notes, StepContext& local) const;
  // whether all articulation a reads is finite, and its PD gains not negative
  bool input_valid(int a, const StepContext& step) const;
  // throws naming the first non-finite input or negative PD gain, its world and value; the next step refactors
  [[noreturn]] void raise_bad_input(const StepContext& step);
  // the deepest contact of articulation a among the step's
  Scalar deepest_contact(int a, const Contacts& contacts) const;
  // per dof the divergence guard's energy weight (engine/solver/parts/guard.h), from each articulation's mass matrix at
  // joint_q0
  void weigh_energy();
  // the actuators by dof and by tendon, the tendon entries by dof
  void group_actuators();
  // constrained_ and the articulations it marks touched
  void mark_constrained();
  // the routes: each articulation's, made again when a setting that decides them changed
  void plan();
  StepContext begin_step(const State& in, State& out, const Control& control, Contacts& contacts, Scalar dt);
  // step.tau: the control's joint forces, or where the model has actuators or tendons the sums each unit makes
  // for its articulations (actuate_unit)
  void actuate(const Control& control, StepContext& step);
  // the force along tendon t
  Scalar tendon_force(int t, const State& in, const Control& control) const;
  // the joint forces of these articulations' dofs with their actuators' and tendons', and in `local` whether
  // some actuator has a position or velocity term (the step's implicit stiffness and damping)
  void actuate_unit(const int* arts, int count, StepContext& local);
  // each contact to its articulation's unit, or to the islands with every row of the articulations it joins; the
  // articulations a contact deeper than divergence_depth touches flagged
  void list_contacts(const Contacts& contacts, StepContext& step);
  // the moving articulations contact c touches flagged (it is deeper than divergence_depth); on any thread
  void flag_deep(const Contacts& contacts, int c);
  // those of these articulations whose inputs are not valid (input_valid) flagged, on their unit's thread
  void flag_invalid(const int* arts, int count, const StepContext& step);
  // data_.touched: the articulations a contact joins to another moving one (throws for a contact between
  // two worlds, which no CollisionPipeline makes); returns whether a contact touched any
  bool touch_articulations(const Contacts& contacts, int threads);
  // the stages first..last over every unit of both routes: block-major, a unit's in turn on its thread;
  // stage-major (profiling), each over all units before the next; the factors checked after Dynamics
  void pass(const StepContext& step, Stage first, Stage last);
  // the islands' rows: the dense route's articulations' and those of the articulations contacts join
  void solve_islands(const StepContext& step);
  // the diverged articulations raised, kept or reset (settings.on_divergence)
  void guard(const StepContext& step);
  void end_step(const State& in, State& out, const StepContext& step);
  // throws naming the first articulation whose factor failed this step on finite input
  void check_factors(const StepContext& step) const;
  // the wall time since the last lap, added to `total` while profiling
  void lap(double& total);
  int thread_count() const;

  const Model& model_;
  WeldedModel welded_;  // what the kernels see: art_ views its arrays
  std::vector<ArticulationView> art_;
  std::vector<std::vector<WeldedBody>> welded_into_;  // per articulation: its welded bodies
  ArticulationIndex index_;
  // Revolute and Prismatic joints with a finite limit, by articulation (a's from limited_start_[a]); their
  // impulses' cells in data_.limit_impulse, [2 m + side]
  std::vector<int> limited_joints_, limited_start_, limit_cell_;
  // per dof: the actuators that drive it, in order, dof_actuators_[dof_actuator_start_[d] .. [d + 1]): each one's
  // index, its joint's coordinate and its numbers in actuator_params_, the distinct ones of the Model (read-only
  // after finalize): replicated robots' actuators share them, so a step reads one small table
  struct DofActuator {
    int u, q, params;
  };
  std::vector<int> dof_actuator_start_;
  std::vector<DofActuator> dof_actuators_;
  std::vector<ActuatorParams> actuator_params_;
  // per shape: its contact numbers' place in contact_materials_, the distinct ones, and its body's invweight0; the
  // materials' pairs at shape_contacts_.dt (ShapeContacts: where there are few materials)
  std::vector<int> shape_material_;
  std::vector<Scalar> shape_weight_;
  std::vector<ContactMaterial> contact_materials_;
  std::vector<ContactPair> contact_pairs_;
  ShapeContacts shape_contacts_;
  // per tendon: the actuators on it, tendon_actuators_[tendon_actuator_start_[t] .. [t + 1]); per dof: the
  // tendon entries on it likewise (dof_entries_, dof_entry_start_), entry_tendon_: each entry's tendon
  std::vector<int> tendon_actuator_start_, tendon_actuators_, dof_entry_start_, dof_entries_, entry_tendon_;
  // per articulation: 1 where an equality constraint or a tendon limit acts on it (its rows are always the
  // islands')
  std::vector<std::uint8_t> constrained_;
  std::unique_ptr<ArticulationBatches> batches_;
  std::unique_ptr<DenseArticulations> dense_;
  std::unique_ptr<IslandRows> islands_;
  // the plan: the aba_min_dofs the blocks were enabled with (-1: none yet), each articulation's route, the
  // dense route's articulations with dofs (their rows are the islands')
  int planned_max_dofs_ = -1;
  std::vector<StepRoute*> route_;
  std::vector<int> dense_rows_;
  std::vector<int> island_articulations_, island_contacts_;  // this step's
  int listed_ = 0;                                           // the contacts the last step listed
  int contact_dims_ = 3;  // the rows of a contact of the most, by the shapes' condim (ContactLists::dims)
  SolverCounts counts_;
  SolverData data_;
  int flagged_ = 0;                         // 1 where some articulation is flagged this step (data_.flagged)
  std::vector<Scalar> reset_q_, reset_qd_;  // the reset state's joint_q and joint_qd (set_reset_state)
  std::vector<Scalar> energy_weight_;       // [dof] (weigh_energy)
  std::atomic<bool> busy_{false};           // a step is running (ExclusiveCall)
  std::int64_t step_bytes_ = 0;             // what a step touches: the solver's memory when made and the state's arrays
  int steps_since_factor_ = 0;
  int trouble_ = 0;  // 1 where a unit's world failed its factor or diverged this step (its units' passes mark it)
  bool factor_kept_ = false;  // the last step's factor kept for this one (its update_mass_matrix_interval > 1)
  Scalar factored_dt_ = 0;
  int max_threads_ = 1;  // the threads the routes keep scratch for
  SolverStageSeconds stage_seconds_;
  std::int64_t lap_mark_ = 0;  // steady_clock nanoseconds at the last lap
  SerialSeconds serial_seconds_;
  // index_inputs: per articulation its bodies and actuators as runs ([begin, count] pairs from *_start_[a]) and
  // its tendons; the bodies and actuators of none
  std::vector<int> art_body_start_, art_body_runs_, art_actuator_start_, art_actuator_runs_;
  std::vector<int> art_tendon_start_, art_tendons_;
  std::vector<int> loose_bodies_, loose_actuators_;
};

}  // namespace novaphy
