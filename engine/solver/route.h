// What one step's stages read and write, and the interface of a route: a way of stepping a set of
// articulations unit by unit (a SIMD block of worlds, engine/solver/blocks/blocks.h, or one articulation
// on the scalar kernels, engine/solver/dense/dense.h). The solver's scheduler runs every unit of every
// route through the same stages in one order (run_unit, below), a unit's stages one after another on one thread.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/model.h"
#include "engine/solver/settings.h"
#include "engine/threads/parallel.h"
#include "kernels/lanes.h"
#include "kernels/pgs.h"

namespace novaphy {

// the stages of a step after its inputs and contacts, in physics order (this order is the only place it is
// written). A unit's stage runs on every unit of every route, a unit's stages one after another on one thread
// (run_unit): kinematics and forces, mass and factor, the unconstrained velocity (Dynamics); the unit's own rows
// and their solve (Rows); integration and the guard's test (Integrate); the new state written out (Store). A
// step's stage runs once for the whole step: the islands' rows and their solve (Islands); the diverged worlds
// raised, kept or reset (Guard). The solver runs the unit stages in passes over the units, broken only before a
// step's stage that the unit stages after it wait for (StepContext::waits_for)
enum class Stage : int { Dynamics = 0, Rows = 1, Islands = 2, Integrate = 3, Guard = 4, Store = 5 };
inline constexpr Stage kStages[] = {Stage::Dynamics,  Stage::Rows,  Stage::Islands,
                                    Stage::Integrate, Stage::Guard, Stage::Store};
constexpr bool unit_stage(Stage s) { return s != Stage::Islands && s != Stage::Guard; }

struct ArticulationIndex;
struct ShapeContacts;

// the contacts whose rows an articulation's own unit solves (with static bodies or with itself), listed
// per articulation in contact order; the unit reads each one's links, friction, restitution and softness from
// the model (engine/solver/parts/contact_rows.h) as it builds its rows
struct ContactLists {
  const int* start = nullptr;  // [articulation + 1]: a's are list[start[a] .. start[a + 1])
  const int* list = nullptr;   // contact indices
  const Model* model = nullptr;
  const ArticulationIndex* index = nullptr;
  int dims = 3;  // the rows of a contact of the most: 3, 4 (torsional) or 6 (and rolling), by the shapes' condim
  const ShapeContacts* shapes = nullptr;  // the shapes' contact numbers (engine/solver/parts/contact_material.h)
};

// what every unit's stages read and write this step
struct StepContext {
  const State* in = nullptr;
  State* out = nullptr;
  const Control* control = nullptr;
  Contacts* contacts = nullptr;  // geometry and warm starts in; contact_impulse out
  Scalar dt = 0;
  const Scalar* tau = nullptr;  // [dof] the control's joint forces with its actuators'
  // [6 body] the wrenches the step applies: in's body_f, with what the model applies itself added where it has some
  // (gravity compensation, site actuators: engine/solver/parts/applied_wrenches.h)
  const Scalar* body_f = nullptr;

  // the step's options: the settings table as the step began, and what it decides for this step
  SolverFeatherstoneSettings settings;
  bool refactor = true;  // H recomputed and factored (else the last factor is reused)
  Scalar keep = 1;       // angular damping: what is left of a rotational dof's velocity over dt
  // `split`: a stage between two passes (the islands) reads the units' kinematics and factors; `stream`: body
  // output written around the caches
  bool split = false;
  bool stream = false;
  // H and its factor kept for later steps
  bool keep_factor() const { return settings.update_mass_matrix_interval > 1; }
  // whether a step's stage runs this step: the islands where some rows are theirs (`split`), the guard always
  bool runs(Stage s) const { return s != Stage::Islands || split; }
  // whether the unit stages after step's stage s wait for it (the pass is broken before it), else it follows the
  // pass: Integrate reads the islands' impulses; Store waits for the guard only where a divergence raises (nothing
  // is written), else each world is written as it is stepped, unless it diverged or its factor failed, and the
  // guard then keeps or resets those
  bool waits_for(Stage s) const { return s == Stage::Islands || settings.on_divergence == DivergencePolicy::Raise; }

  // the rows and the guard
  PgsSettings pgs;  // the sweeps' (kernels/pgs.h) of the settings; the row parts read the settings themselves
  ContactLists lists;
  const std::uint8_t* touched = nullptr;  // [articulation] 1: its rows are the islands' this step
  const Scalar* energy_weight = nullptr;  // [dof] the guard's energy weights (engine/solver/parts/guard.h)
  // [articulation] 1: diverged before its step's output is tested (an invalid input, a contact too deep)
  const std::uint8_t* flagged = nullptr;

  // the step's vectors, in the model's numbering
  Scalar* qd = nullptr;                   // [dof] velocities between the stages of split passes
  Scalar* q_next = nullptr;               // [coord] coordinates after the step, likewise
  Scalar* limit_impulse = nullptr;        // [limit cell] warm starts of limit rows
  Scalar* friction_impulse = nullptr;     // [dof] warm starts of friction-loss rows
  Scalar* equality_impulse = nullptr;     // [equality][6] warm starts of equality rows
  Scalar* tendon_impulse = nullptr;       // [tendon][3] warm starts of tendon-limit rows (two sides), dry friction
  std::uint8_t* pgs_converged = nullptr;  // [articulation] 1: its last sweeps converged (warm_share)
  std::uint8_t* diverged = nullptr;       // [articulation]
  int* factor_failure = nullptr;          // [articulation] dof whose pivot failed, else -1
};

// what one unit's Dynamics reads of its own articulations' inputs beside the step's
struct UnitInputs {
  bool wrenches = false;  // in.body_f has a nonzero entry
  bool drives = false;    // the control has a nonzero PD gain
  // [dof] the actuators' stiffness and damping, which the step takes implicitly (nullptr: none)
  const Scalar* actuator_stiffness = nullptr;
  const Scalar* actuator_damping = nullptr;
};

// one unit's pass: its stages first..last, one after another on one thread; a stage after the first takes what
// the one before left in the thread's scratch (`carried`), the first reads the step's vectors, and a stage
// before the last leaves its results there (`carry_on`) rather than in the step's vectors
struct UnitPass {
  int unit = 0;
  Stage first = Stage::Dynamics, last = Stage::Store;
  bool runs(Stage s) const { return s >= first && s <= last; }
  bool carried(Stage s) const { return s > first; }
  bool carry_on(Stage s) const { return s < last; }
};

// where each body and dof sits among the articulations the kernels see
struct ArticulationIndex {
  std::vector<int> body_articulation, body_link;  // per body; welded bodies at their link's
  std::vector<int> dof_articulation;              // per dof
  std::vector<int> dof_count;                     // per articulation
  // the articulation `body` moves with: -1 for the world (-1) or a body of an articulation without dofs
  int moving(int body) const {
    return body >= 0 && dof_count[body_articulation[body]] > 0 ? body_articulation[body] : -1;
  }
};

// the wall time of the rows stage's phases on one thread (settings.profile_stages)
struct RowPhaseSeconds {
  double limits = 0, contacts = 0, sweeps = 0;
};

// the time one thread spent in each stage of its units (settings.profile_stages); Store's counts as Integrate's
struct alignas(64) UnitStageSeconds {
  double dynamics = 0, rows = 0, integrate = 0;
};

// the most articulations a unit steps: a block's lanes of float32 worlds
inline constexpr int kMostUnitArticulations = kLanes<float>;

class StepRoute {
 public:
  virtual ~StepRoute() = default;
  // units: what one thread steps at a time
  virtual int unit_count() const = 0;
  // the articulations unit `unit` steps into out (at most kMostUnitArticulations); returns their count
  virtual int unit_articulations(int unit, int* out) const = 0;
  // before and after the step's passes, on the calling thread
  virtual void begin_step(const StepContext& step) = 0;
  virtual void end_step(const StepContext& step) = 0;
  // the stages of unit pass.unit, each on the calling thread (run_unit calls them in order)
  virtual void dynamics(const UnitPass& pass, const StepContext& step, const UnitInputs& inputs) = 0;
  virtual void rows(const UnitPass& pass, const StepContext& step) = 0;
  virtual void integrate(const UnitPass& pass, const StepContext& step) = 0;
  virtual void store(const UnitPass& pass, const StepContext& step) = 0;

  // for the islands' rows, after Dynamics: x = M^-1 x with articulation a's factor, and J += sign *
  // (the row of d . the velocity of the point p riding on `link`, or with p null of d . the link's angular
  // velocity) over a's dofs
  virtual void solve_mass(int a, Scalar* x) = 0;
  virtual void point_jacobian(int a, int link, const Vec3* p, const Vec3& d, Scalar sign, Scalar* J) const = 0;

  // bytes held
  virtual std::size_t bytes() const = 0;
};

// one unit's pass: its unit stages from pass.first to pass.last in their order, each timed into `seconds` where it
// is not null (Store's time counts as Integrate's)
inline void run_unit(StepRoute& route, const UnitPass& pass, const StepContext& step, const UnitInputs& inputs,
                     UnitStageSeconds* seconds) {
  for (const Stage s : kStages) {
    if (!unit_stage(s) || !pass.runs(s)) continue;
    double* total = !seconds               ? nullptr
                    : s == Stage::Dynamics ? &seconds->dynamics
                    : s == Stage::Rows     ? &seconds->rows
                                           : &seconds->integrate;
    const ParallelTimer timer(seconds != nullptr, total);
    switch (s) {
      case Stage::Dynamics: route.dynamics(pass, step, inputs); break;
      case Stage::Rows: route.rows(pass, step); break;
      case Stage::Integrate: route.integrate(pass, step); break;
      case Stage::Store: route.store(pass, step); break;
      case Stage::Islands:
      case Stage::Guard: break;  // the step's stages, not a unit's
    }
  }
}

}  // namespace novaphy
