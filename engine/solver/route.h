// What one step's stages read and write, and the interface of a route: a way of stepping a set of
// articulations unit by unit (a SIMD block of worlds, engine/solver/blocks/blocks.h, or one articulation
// on the scalar kernels, engine/solver/dense/dense.h). The solver's scheduler runs every unit of every
// route through the same stages, a unit's stages one after another on one thread (block-major) or each
// stage over all units before the next (stage-major, for profiling): the same arithmetic either way.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/model.h"
#include "engine/solver/parts/row_params.h"
#include "kernels/lanes.h"

namespace novaphy {

// the per-unit stages of a step, in order
enum class Stage : int { Dynamics = 0, Rows = 1, Integrate = 2, Store = 3 };

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

struct StepContext {
  const State* in = nullptr;
  State* out = nullptr;
  const Control* control = nullptr;
  Contacts* contacts = nullptr;  // geometry and warm starts in; contact_impulse out
  Scalar dt = 0;
  const Scalar* tau = nullptr;  // [dof] the control's joint forces with its actuators'
  // [dof] the actuators' stiffness and damping, which the step takes implicitly (nullptr: none this step)
  const Scalar* actuator_stiffness = nullptr;
  const Scalar* actuator_damping = nullptr;

  // the dynamics this step
  bool refactor = true;     // H recomputed and factored (else the last factor is reused)
  bool keep_factor = true;  // H and its factor kept for later steps (update_mass_matrix_interval > 1)
  bool fuse = true;         // the factor and the first half of the solve in one pass
  bool tile_gemm = false;   // H as the tiled product sum J_i^T I_i J_i instead of CRBA
  bool wrenches = false;    // in.body_f has a nonzero entry
  bool drives = false;      // the control has a nonzero PD gain
  Scalar keep = 1;          // angular damping: what is left of a rotational dof's velocity over dt
  Scalar coriolis_implicitness = 0;
  int aba_min_dofs = 0;  // the dense route factors articulations of at least this many dofs by ABA

  // the rows and the guard
  RowParams rows;
  ContactLists lists;
  const std::uint8_t* touched = nullptr;  // [articulation] 1: its rows are the islands' this step
  Scalar divergence_speed = 0;
  Scalar divergence_energy = 0;           // J/kg
  const Scalar* energy_weight = nullptr;  // [dof] the guard's energy weights (engine/solver/parts/guard.h)
  // [articulation] 1: diverged before its step's output is tested (an invalid input, a contact too deep)
  const std::uint8_t* flagged = nullptr;

  // the schedule: `split`: a stage between two passes (the islands) reads the units' kinematics and
  // factors; `store_in_pass`: Store follows Integrate in its pass (each world written as it is stepped,
  // unless it diverged or its factor failed); `stream`: body output written around the caches
  bool split = false;
  bool store_in_pass = false;
  bool block_major = true;  // a unit's stages one after another in one pass (else a stage over all units at a time)
  bool stream = false;
  bool profile = false;  // the rows stage times its phases (stage_seconds)

  // the step's vectors, in the model's numbering
  Scalar* qd = nullptr;                   // [dof] velocities between the stages of split passes
  Scalar* q_next = nullptr;               // [coord] coordinates after the step, likewise
  Scalar* limit_impulse = nullptr;        // [limit cell] warm starts of limit rows
  Scalar* friction_impulse = nullptr;     // [dof] warm starts of friction-loss rows
  Scalar* equality_impulse = nullptr;     // [equality][6] warm starts of equality rows
  Scalar* tendon_impulse = nullptr;       // [tendon][2] warm starts of tendon-limit rows
  std::uint8_t* pgs_converged = nullptr;  // [articulation] 1: its last sweeps converged (warm_share)
  std::uint8_t* diverged = nullptr;       // [articulation]
  int* factor_failure = nullptr;          // [articulation] dof whose pivot failed, else -1
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

// the wall time of the rows stage's phases on one thread (StepContext::profile)
struct RowPhaseSeconds {
  double limits = 0, contacts = 0, sweeps = 0;
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
  // stages first..last of one unit, in order, on the calling thread (a stage after the first takes what
  // the one before left in the thread's scratch; the first reads the step's vectors)
  virtual void run(int unit, Stage first, Stage last, const StepContext& step) = 0;

  // for the islands' rows, after Dynamics: x = M^-1 x with articulation a's factor, and J += sign *
  // (the row of d . the velocity of the point p riding on `link`, or with p null of d . the link's angular
  // velocity) over a's dofs
  virtual void solve_mass(int a, Scalar* x) = 0;
  virtual void point_jacobian(int a, int link, const Vec3* p, const Vec3& d, Scalar sign, Scalar* J) const = 0;

  // bytes held
  virtual std::size_t bytes() const = 0;
};

}  // namespace novaphy
