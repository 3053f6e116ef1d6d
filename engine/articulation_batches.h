// Articulation batches: the articulations that share joints, frames and axes (every world of a
// replicated robot) are grouped, kLanes<T> worlds to a block, and stepped by the batched kernels
// (kernels/batch.h) in the model's precision. Per-world parameters (masses, inertias, armature,
// damping, springs; gains and targets from the Control) stay per lane, so a randomised batch keeps
// the batched path. Blocks are spread over OpenMP threads by parallel_for (engine/parallel.h: a
// static schedule but for the last eighth); each thread owns its scratch, and a step allocates nothing.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/collision.h"
#include "engine/model.h"
#include "kernels/pgs.h"

namespace novaphy {

// a body welded into a link by a Fixed joint (engine/weld.h): where its state comes from
struct WeldedBody {
  int body = 0;
  int link = 0;
  Transform offset;  // its pose in the link's frame
};

class ArticulationBatches {
 public:
  virtual ~ArticulationBatches() = default;

  // batches over the articulations a with batched[a] != 0, in precision `precision`; `model`
  // holds the arrays the views `art` point into (the welded model), `welded[a]` articulation a's
  // welded bodies, `com` every body's own centre of mass and `limit_slot[dof]` the solver's number for
  // that dof's limit (-1: a dof without a finite limit)
  static std::unique_ptr<ArticulationBatches> make(const Model& model, const std::vector<ArticulationView>& art,
                                                   const std::vector<std::uint8_t>& batched,
                                                   const std::vector<std::vector<WeldedBody>>& welded,
                                                   const std::vector<Scalar>& com, const std::vector<int>& limit_slot,
                                                   Precision precision);

  // batches of fewer than `max_dofs` dofs on, the others off (those take the solver's ABA path; a
  // batch switched off refactors when it is next on)
  virtual void enable(int max_dofs) = 0;
  // true when articulation a is in a batch that is on
  virtual bool active(int a) const = 0;
  // how many articulations are in batches that are on
  virtual int active_count() const = 0;
  // where solve_rows and step keep the limit impulses of batched articulations (the warm starts of their
  // limit rows) in their array `impulse`: cell [2 * slot + side] for the limit slots given to make() (side
  // 0 the lower limit, 1 the upper), -1 for the others (the vector may be shorter than twice the slots).
  // They take cells [0, limit_cell_count()), a block's laid out [limited dof][side][lane], so that a
  // block reads and writes each as one vector
  virtual const std::vector<int>& limit_cells() const = 0;
  virtual int limit_cell_count() const = 0;

  // how dynamics treats a step
  struct DynamicsOptions {
    bool refactor = true;    // H recomputed and factored (else the last factor is reused)
    bool fuse = true;        // the factor and the first half of the solve in one pass
    bool tile_gemm = false;  // H as the tiled product sum J_i^T I_i J_i instead of CRBA
    bool wrenches = false;   // in.body_f has a nonzero entry
    bool drives = false;     // the control has a nonzero PD gain
    Scalar keep = 1;         // angular damping: rotational dofs' unconstrained velocities are scaled by it
    // H and its factor kept in the blocks for later steps (update_mass_matrix_interval > 1); without,
    // step() factors in thread scratch and the next step refactors (dynamics() always keeps them: the
    // solver's scalar rows read them)
    bool keep_factor = true;
  };
  // unconstrained velocity qd_out = qd + dt M^-1 (tau - bias - springs - dampers - drives) with M =
  // H + dt D + dt^2 K, for every active articulation; tau [dof] = control forces. qdd_out (when
  // given) receives M^-1 (...) itself: with dt = 0 and no drives, the forward dynamics.
  // factor_failure[a] = the dof whose pivot failed, or left alone. `threads`: the thread count of
  // this step's parallel loops (solve_mass may be called from any of them)
  virtual void dynamics(const State& in, const Control& control, const Scalar* tau, Scalar dt,
                        const DynamicsOptions& options, Scalar* qd_out, Scalar* qdd_out, int* factor_failure,
                        int threads) = 0;
  // the contacts of articulations with static bodies (the ground) or with themselves, listed per
  // articulation for solve_rows
  struct BlockContacts {
    Contacts* contacts = nullptr;  // geometry and warm starts in; contact_impulse out for the listed contacts
    const int* start = nullptr;    // [articulation + 1]: articulation a's contacts are list[start[a] .. start[a + 1])
    const int* list = nullptr;     // contact indices, each articulation's in increasing order
    const int* link_a = nullptr;   // [contact] the link holding body a in its articulation, -1 for a static body
    const int* link_b = nullptr;   // [contact] likewise for body b
    const Scalar* mu = nullptr;    // [contact] friction coefficient
    const Scalar* restitution = nullptr;  // [contact]
  };
  struct RowSettings {
    PgsSettings pgs;  // the sweeps: iterations, cfm, friction cone, tolerance
    Scalar erp = 0.2, linear_slop = 0.001, warmstarting_factor = 0.85, restitution_threshold = 0.2;
    bool use_warmstarting = true;
  };
  // the constraint rows of active articulations with skip[a] == 0 (no contact joins them to another
  // moving articulation), solved here a block at a time: joint-limit rows, then each world's listed
  // contacts (a normal row and two friction rows each), with the same targets, warm start and PGS
  // sweeps as the solver's scalar path (kernels/batch_pgs.h); a lane's absent rows are masked.
  // qd [dof] and impulse [limit_cells()] (the warm-start impulses of the lower and upper limits) are read
  // and written for those articulations; in.joint_qd (the step's initial velocity) is read for restitution
  virtual void solve_rows(const State& in, const std::uint8_t* skip, const BlockContacts& contacts,
                          const RowSettings& settings, Scalar dt, Scalar* qd, Scalar* impulse, int threads) = 0;
  // true where articulation a's rows are solved by solve_rows (given the same skip)
  virtual bool solves_rows(int a, const std::uint8_t* skip) const = 0;
  // the divergence guard's test: an articulation diverged where its q_out or qd is not finite or some
  // |qd| exceeds speed; diverged[a] is set to it
  struct Divergence {
    Scalar speed = 0;
    std::uint8_t* diverged = nullptr;  // [articulation]
  };
  // q_out = in.joint_q stepped by qd over dt (the coordinates of active articulations; their qd rewritten
  // as the lanes held it, in the model's precision), and the guard
  virtual void integrate(const State& in, Scalar* qd, Scalar dt, Scalar* q_out, const Divergence& divergence,
                         int threads) = 0;
  // dynamics, solve_rows (when `contacts` is given; no articulation skipped) and integrate of every active
  // articulation, a block at a time so that its data stay in cache between the three: the same
  // arithmetic as calling them in turn, for a step that has no rows on the solver's scalar path. With
  // `out`, store_bodies follows in the same pass, from the block's lanes: out.joint_q, joint_qd, body_q and
  // body_qd are written (q_out and qd are not) for every world that did not diverge and whose factor did
  // not fail; the others' are left to the caller
  virtual void step(const State& in, const Control& control, const Scalar* tau, Scalar dt,
                    const DynamicsOptions& options, const BlockContacts* contacts, const RowSettings& rows, Scalar* qd,
                    Scalar* impulse, Scalar* q_out, const Divergence& divergence, int* factor_failure, State* out,
                    bool stream, int threads) = 0;
  // out.joint_q = q, out.joint_qd = qd, and body_q / body_qd from them, for active articulations; with
  // `stream`, the bodies of a block whose worlds' bodies follow each other are written around the caches
  virtual void store_bodies(const Scalar* q, const Scalar* qd, State& out, bool stream, int threads) = 0;
  // x = M^-1 x with the last factor of articulation a
  virtual void solve_mass(int a, Scalar* x) const = 0;
  // J += sign * (row of d . velocity of the point p riding on `link`), over articulation a's dofs
  virtual void point_jacobian(int a, int link, const Vec3& p, const Vec3& d, Scalar sign, Scalar* J) const = 0;

  virtual int group_count() const = 0;
  virtual int block_count() const = 0;
  virtual int lanes() const = 0;
  // bytes held: per-world parameters, H and its factor, motion subspaces, thread scratch
  virtual std::size_t bytes() const = 0;
};

}  // namespace novaphy
