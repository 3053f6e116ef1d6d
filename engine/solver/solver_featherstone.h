// SolverFeatherstone: one time step of every articulation in reduced coordinates.
//   forward kinematics -> RNEA bias forces -> CRBA mass matrix (+ implicit damping, springs and PD
//   drives) -> its factor -> unconstrained velocity -> sequential-impulse PGS over contact and
//   joint-limit rows through M^-1 J^T -> semi-implicit integration -> forward kinematics
// Every articulation goes through the same stages (engine/solver/route.h), on one of two routes chosen
// when the solver is made (and again when a setting that decides them changes): SIMD blocks of worlds
// (engine/solver/blocks/blocks.h) or one articulation on the scalar kernels (engine/solver/dense/dense.h);
// rows that join articulations are solved as islands (engine/solver/islands/rows.h). As MuJoCo splits model and
// data: what is built once for the model is SolverModel (engine/solver/solver_model.h), what a step writes
// SolverData (engine/solver/solver_data.h), what it reads of the settings StepContext (engine/solver/route.h);
// the solver holds those, the routes and the step's schedule. docs/step.md tells the step.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/sensors/sensors.h"
#include "engine/solver/blocks/blocks.h"
#include "engine/solver/dense/dense.h"
#include "engine/solver/islands/rows.h"
#include "engine/solver/joint_support.h"
#include "engine/solver/parts/applied_wrenches.h"
#include "engine/solver/parts/rows.h"
#include "engine/solver/settings.h"
#include "engine/solver/solver_data.h"
#include "engine/solver/solver_model.h"
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
  // holds this solver's one-call flag for the caller's scope (steps on this thread nest inside it), so work that
  // belongs with a step (the binding's float32 conversions) is refused with it on another thread
  ExclusiveCall hold() { return ExclusiveCall(busy_, "SolverFeatherstone.step"); }

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
  // notes in `inputs` whether these articulations have wrenches (a nonzero body_f) and drives (a nonzero PD gain),
  // and returns whether body_f, the gains or actuator_ctrl hold an entry not finite or a gain below 0 (an infinite
  // command would be clamped to its control range: no output shows it); with `valid`, whether all they read is
  // finite and their gains not negative: their joint_q, joint_qd, body_f, actuator_ctrl and per-dof control (the
  // PD targets where a gain is nonzero). Any other non-finite input reaches the step's output (a drive's gain or a
  // wrench that is not finite is nonzero), so the pass scans only body_f, the gains and the commands; the guard and
  // check_factors scan all of an articulation whose step went wrong
  bool scan_unit(const int* arts, int count, const StepContext& step, UnitInputs& inputs, bool* valid) const;
  // scan_unit's notes of block units [begin, end), scanned back to back (each input array read as one stream, as
  // a pass over all of them would read it, rather than a short run a unit between the unit's other work)
  struct UnitNotes {
    static constexpr int kUnits = 8;
    int begin = 0, end = 0;
    std::array<std::uint8_t, kUnits> drives, wrenches, invalid;
  };
  // the notes for block unit u of a thread's run that ends at `run_end`, from `notes` or scanned into it with the
  // units after u; returns scan_unit's
  bool block_unit_notes(int u, int run_end, const StepContext& step, UnitNotes& notes, UnitInputs& inputs) const;
  // whether all articulation a reads is finite, and its PD gains not negative
  bool input_valid(int a, const StepContext& step) const;
  // throws naming the first non-finite input or negative PD gain, its world and value; the next step refactors
  [[noreturn]] void raise_bad_input(const StepContext& step);
  // the deepest contact of articulation a among the step's
  Scalar deepest_contact(int a, const Contacts& contacts) const;
  // the routes: each articulation's, made again when a setting that decides them changed
  // what depends on the model's per-world parameters read again for the worlds Model::set_parameter wrote since
  // the last step (SolverModel, the blocks' lanes, the contact pairs), and the factor made again
  void read_parameters();
  void plan();
  // the worlds `in` marks as reset (State::world_reset) stepped with no history: their rows' warm starts cleared,
  // the mass matrix factored afresh (for every world: the factor's schedule restarts)
  void forget_reset_worlds(const State& in);
  StepContext begin_step(const State& in, State& out, const Control& control, Contacts& contacts, Scalar dt);
  // step.tau: the control's joint forces, or where the model has actuators or tendons the sums each unit makes
  // for its articulations (actuate_unit)
  void actuate(const Control& control, StepContext& step);
  // the force along tendon t
  Scalar tendon_force(int t, const State& in, const Control& control) const;
  // the joint forces of these articulations' dofs with their actuators' and tendons', and in `inputs` whether
  // some actuator has a position or velocity term (the step's implicit stiffness and damping)
  void actuate_unit(const int* arts, int count, const StepContext& step, UnitInputs& inputs);
  // each contact to its articulation's unit, or to the islands with every row of the articulations it joins; the
  // articulations a contact deeper than divergence_depth touches flagged
  void list_contacts(const Contacts& contacts, StepContext& step);
  // the moving articulations contact c touches flagged (it is deeper than divergence_depth); on any thread
  void flag_deep(const Contacts& contacts, int c);
  // those of these articulations whose inputs are not valid (input_valid) flagged, on their unit's thread
  void flag_invalid(const int* arts, int count, const StepContext& step);
  // data_.touched: the articulations a contact joins to another moving articulation (throws for a contact between
  // two worlds, which no CollisionPipeline makes); returns whether a contact touched any
  bool touch_articulations(const Contacts& contacts, int threads);
  // the stages from Dynamics to Store (route.h's kStages): the unit stages in passes, each step's stage that runs
  // this step where the units wait for it or after the last pass
  void run_stages(const StepContext& step);
  // step's stage s: the islands' rows and solve, or the guard
  void step_stage(Stage s, const StepContext& step);
  // the unit stages first..last of every unit of both routes, a unit's in turn on its thread (run_unit); after
  // Dynamics the factors checked
  void pass(const StepContext& step, Stage first, Stage last);
  // the islands' rows: the dense route's articulations' and those of the articulations contacts join
  void solve_islands(const StepContext& step);
  // the diverged articulations raised, kept or reset (settings.on_divergence)
  void guard(const StepContext& step);
  void end_step(const State& in, State& out, const StepContext& step);
  // the worlds whose articulations the divergence guard reset (on_divergence Reset) leave the step as
  // Model::reset_worlds leaves a world: world_reset set (their next collide and step use none of their past) and
  // their sensors zeroed (a reset's velocity jump is no acceleration)
  void restart_guard_resets(State& out) const;
  // throws naming the first articulation whose factor failed this step on finite input
  void check_factors(const StepContext& step) const;
  // the wall time since the last lap, added to `total` while profiling
  void lap(double& total);
  // the wall time since the last lap shared out among the stages as the threads' time in a pass went to them,
  // while profiling; `before` the rows' phases as the pass began
  void lap_pass(const RowPhaseSeconds& before);
  int thread_count() const;

  const Model& model_;
  SolverModel built_;  // what is built once for the model (read again only where parameters change)
  // the routes, their scratch and where their limit impulses sit in data_.limit_impulse ([2 m + side] for the
  // limited joint m)
  std::unique_ptr<ArticulationBatches> batches_;
  std::unique_ptr<DenseArticulations> dense_;
  std::unique_ptr<IslandRows> islands_;
  std::vector<int> limit_cell_;
  // the plan: the aba_min_dofs the blocks were enabled with (-1: none yet), each articulation's route, the
  // dense route's articulations with dofs (their rows are the islands')
  int planned_max_dofs_ = -1;
  std::vector<StepRoute*> route_;
  std::vector<int> dense_rows_;
  // the materials' pairs at shape_contacts_.dt (ShapeContacts: where there are few materials)
  std::vector<ContactPair> contact_pairs_;
  ShapeContacts shape_contacts_;
  // the step's data
  SolverCounts counts_;
  SolverData data_;
  std::vector<int> island_articulations_, island_contacts_;  // this step's
  int listed_ = 0;                                           // the contacts the last step listed
  int flagged_ = 0;  // 1 where some articulation is flagged this step (data_.flagged)
  int trouble_ = 0;  // 1 where a unit's world failed its factor or diverged this step (its units' passes mark it)
  // the factor's schedule (update_mass_matrix_interval)
  int steps_since_factor_ = 0;
  std::uint64_t parameters_read_ = 0;  // the model's parameter_writes when the solver last read its parameters
  bool factor_kept_ = false;           // the last step's factor kept for this one (its update_mass_matrix_interval > 1)
  Scalar factored_dt_ = 0;
  std::vector<Scalar> reset_q_, reset_qd_;  // the reset state's joint_q and joint_qd (set_reset_state)
  // the model's sensors, and the step's start they are computed at where state_in is state_out (its joint_q,
  // joint_qd)
  Sensors sensors_;
  std::vector<Scalar> start_q_, start_qd_;
  // what the model applies itself (gravity compensation, site actuators): a step applies body_f with it added, kept
  // in applied_body_f_
  ModelWrenches model_wrenches_;
  std::vector<Scalar> applied_body_f_;
  CallFlag busy_;                // a step is running (ExclusiveCall)
  std::int64_t step_bytes_ = 0;  // what a step touches: the solver's memory when made and the state's arrays
  int max_threads_ = 1;          // the threads the routes keep scratch for
  // profiling: the stages' totals, steady_clock nanoseconds at the last lap, each thread's stage times in a pass
  SolverStageSeconds stage_seconds_;
  std::int64_t lap_mark_ = 0;
  std::vector<UnitStageSeconds> unit_seconds_;
  SerialSeconds serial_seconds_;
};

}  // namespace novaphy
