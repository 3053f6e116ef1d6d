// Inside the blocks route (engine/solver/blocks/blocks.h): a batch's layout in blocks of lanes, a
// thread's scratch, and the stages of one block, each in its own file (dynamics.cpp,
// rows.cpp, integrate.cpp). Installed with every header of engine/ (the install takes them all), but not for
// users to call: the solver and its tests see ArticulationBatches.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/solver/blocks/blocks.h"
#include "engine/solver/parts/soft_row.h"
#include "kernels/batch.h"
#include "kernels/batch/lane_math.h"
#include "kernels/batch/pgs.h"
#include "kernels/lane_transpose.h"

namespace novaphy {

// articulations of one topology, kLanes<T> to a block; lane slots run block after block, and a partial
// last block repeats its first world in the others
template <typename T>
struct BatchGroup {
  using V = Lanes<T>;
  static constexpr int W = kLanes<T>;
  struct Weld {  // a welded body every world of the group has
    int link;
    T q[4], p[3];  // its pose in the link frame
  };

  BatchTopology<T> topo;
  std::vector<Weld> welds;
  std::vector<int> arts;           // per slot
  std::vector<int> q_off, qd_off;  // per slot: the articulation's first coordinate and dof
  std::vector<int> body;           // per slot: its link bodies, then its welded bodies
  // per body of a world (links, then welds): its place among the world's bodies as the model numbers them
  // (a welded body's number falls between its links'), where its rows are written
  std::vector<int> body_place;
  std::vector<std::uint8_t> contiguous;  // per block: its worlds' bodies, each world's in one run, one after another
  int world_count = 0;
  int blocks = 0;
  int param_size = 0;
  bool shared_params = false;  // every world's parameters the same: one block's worth kept, read by all
  // per block: the parameters (BatchParams' arrays in order, then, with welded bodies, every body's own
  // centre of mass), H and its factor, the motion subspace and o of the last kinematics
  std::vector<V> params, H, S, origin;
  std::vector<int> rotational;  // dofs angular damping scales: Revolute ones and Ball's and Free's angular ones
  std::vector<int> limited;     // Revolute / Prismatic dofs with a finite limit in some world
  std::vector<V> limits;        // per block: [limited][2] lower and upper limit
  std::vector<int> frictional;  // dofs with dry friction (frictionloss > 0) in some world
  std::vector<V> frictionloss;  // per block: [frictional]
  // per block [limited][lane] and [frictional][lane]: the rows' softness (soft_row.h), whether some is soft, and per
  // block [limited] and [frictional] the lanes whose row is
  std::vector<Softness> limit_softness, friction_softness;
  bool soft_limits = false, soft_friction = false;
  std::vector<IntLanes<T>> limit_soft, friction_soft;
  // where its blocks' kept limit impulses start in the step's limit_impulse: per block [limited][2][lane]
  int impulse_base = 0;
  bool enabled = true;
  bool factored = false;  // H of every block factored by an earlier step
  bool refactor = true;   // this step computes and factors H

  explicit BatchGroup(const ArticulationView& art) : topo(art) {}
  int links() const { return static_cast<int>(topo.link.size()); }
  int bodies() const { return links() + static_cast<int>(welds.size()); }
  // worlds in block b that are not padding
  int lanes_in(int b) const { return std::min(W, world_count - b * W); }
  // block b's parameters: its own, or the group's one copy where every world has the same
  const V* block_params_data(int b) const {
    return params.data() + (shared_params ? 0 : static_cast<size_t>(b) * param_size);
  }
  BatchParams<T> block_params(int b) const { return batch_params(topo, block_params_data(b)); }
  // [body][3] each body's own centre of mass (a link's differs from its merged one with welds)
  const V* body_com(int b) const {
    const V* x = block_params_data(b);
    return welds.empty() ? x + links() : x + batch_param_count(topo);
  }
  V* block_H(int b) { return H.data() + static_cast<size_t>(b) * topo.packed_size(); }
  const V* block_H(int b) const { return H.data() + static_cast<size_t>(b) * topo.packed_size(); }
  V* block_S(int b) { return S.data() + static_cast<size_t>(b) * 6 * topo.dof_count; }
  const V* block_S(int b) const { return S.data() + static_cast<size_t>(b) * 6 * topo.dof_count; }
};

// where a block's kinematics and factor are (its own storage, or a thread's scratch)
template <typename T>
struct BlockKinematics {
  Lanes<T>* H = nullptr;  // [packed] H, then its factor
  Lanes<T>* S = nullptr;  // [dof][6] motion subspace about o
  Lanes<T>* o = nullptr;  // [3] the root link's origin
};

// a thread's rows of one block as a field table, X(type, name, count, doc), `count` over RowCounts n (the block's
// rows, dofs and contact slots, one a lane): resize grows each field to its count, bytes counts them all
struct RowCounts {
  size_t rows, dofs, slots;
};
#define NOVAPHY_ROW_WORK(X)                                                                  \
  X(RowKind, kind, n.rows, "[row] the projection of its impulse")                            \
  X(int, normal, n.rows, "[row] a friction row's normal row")                                \
  X(int, nonzero_begin, n.rows, "[row] where J may be nonzero begins (BatchRows)")           \
  X(int, nonzero_end, n.rows, "[row] (and where it ends)")                                   \
  X(int, zero_begin, n.rows, "[row] where whole quads of J that are zero begin (BatchRows)") \
  X(int, zero_end, n.rows, "[row] (and where they end)")                                     \
  X(IntLanes<T>, active, n.rows, "[row] the lanes it is on in")                              \
  X(V, J, (n.rows * n.dofs), "[row][dof] its Jacobian")                                      \
  X(V, z, (n.rows * n.dofs), "[row][dof] M^-1 J^T")                                          \
  X(V, target, n.rows, "[row] the velocity J qd it drives towards")                          \
  X(V, cfm, n.rows, "[row] its own constraint force mixing (a soft row's)")                  \
  X(V, mu, n.rows, "[row] a friction row's coefficient")                                     \
  X(V, inv_mass, n.rows, "[row] 1 / (J M^-1 J^T + cfm)")                                     \
  X(V, lambda, n.rows, "[row] its impulse")                                                  \
  X(V, bound, n.rows, "[row] a Bounded row's largest |impulse|")                             \
  X(int, limit_row, n.rows, "[limited][2] its row, or -1")                                   \
  X(int, friction_row, n.rows, "[frictional] its row, or -1")                                \
  X(int, contact, (n.slots * kLanes<T>), "[slot][lane] the contact, or -1")                  \
  X(V, frame, n.slots * 9, "[slot][3][3] the normal and tangents")                           \
  X(V, coef, n.dofs, "[dof] a slot's +-1 per dof on a contact's paths")                      \
  X(V, qd_in, n.dofs, "[dof] in.joint_qd")                                                   \
  X(V, point, 3 * n.dofs, "[dof][3] the velocity of a slot's contact point moved by each dof")

// On cache lines of its own: each block writes `dofs`
template <typename T>
struct alignas(64) RowWork {
  using V = Lanes<T>;
  int dofs = 0;
#define NOVAPHY_DECLARE_ROW_WORK(type, name, count, doc) std::vector<type> name;
  NOVAPHY_ROW_WORK(NOVAPHY_DECLARE_ROW_WORK)
#undef NOVAPHY_DECLARE_ROW_WORK
  int rows = 0;    // rows of the block being built
  V warm_share{};  // the share of the last step's impulses its limit and friction-loss rows start from
  // room for `rows` rows of `dofs` dofs and `slots` contacts a lane (inline: every block calls it)
  void resize(int rows_, int dofs_, int slots) {
    dofs = dofs_;
    const RowCounts n{static_cast<size_t>(rows_), static_cast<size_t>(dofs_), static_cast<size_t>(slots)};
#define NOVAPHY_RESIZE_ROW_WORK(type, name, count, doc) \
  if (name.size() < (count)) name.resize(count);
    NOVAPHY_ROW_WORK(NOVAPHY_RESIZE_ROW_WORK)
#undef NOVAPHY_RESIZE_ROW_WORK
  }
  V* J_row(int r) { return J.data() + static_cast<size_t>(r) * dofs; }
  V* z_row(int r) { return z.data() + static_cast<size_t>(r) * dofs; }
  std::size_t bytes() const {
    std::size_t n = 0;
#define NOVAPHY_ROW_WORK_BYTES(type, name, count, doc) n += name.size() * sizeof(type);
    NOVAPHY_ROW_WORK(NOVAPHY_ROW_WORK_BYTES)
#undef NOVAPHY_ROW_WORK_BYTES
    return n;
  }
};

// a thread's scratch: per group its kernels' work, and the rows, S, o and a factor no later step reuses
template <typename T>
struct alignas(64) ThreadScratch {
  std::vector<BatchWork<T>> work;  // [group]
  RowWork<T> rows;
  std::vector<Lanes<T>> S, H;
  Lanes<T> origin[3];
  RowPhaseSeconds phases;
  IntLanes<T> written{};  // the lanes the last Integrate wrote out, for a Store in the same pass
  // a world's factor copied out of its block (solve_mass)
  int factor_of = -1;
  std::uint64_t factor_step = 0;
  std::vector<Scalar> factor;
};

// out[k][l] = field[off[l] + k]
template <typename T>
inline void gather_lanes(const int* off, const Scalar* field, int count, Lanes<T>* out) {
  const Scalar* row[kLanes<T>];
  for (int l = 0; l < kLanes<T>; ++l) row[l] = field + off[l];
  lanes_from_rows<T>(row, count, out);
}
// field[off[l] + k] = in[k][l] for the lanes l set in `lanes`
template <typename T>
inline void scatter_lanes(const int* off, const Lanes<T>* in, int count, const IntLanes<T>& lanes, Scalar* field) {
  Scalar* row[kLanes<T>];
  for (int l = 0; l < kLanes<T>; ++l) row[l] = field + off[l];
  rows_from_lanes<T>(in, count, lanes, row);
}
// the lanes of block b's worlds that are not padding
template <typename T>
inline IntLanes<T> real_lanes(const BatchGroup<T>& G, int b) {
  IntLanes<T> real{};
  for (int l = 0; l < G.lanes_in(b); ++l) real[l] = -1;
  return real;
}

// the pose (p, Q) of a welded body: its link's in w (batch_kinematics) composed with its offset
template <typename T>
inline void weld_pose(const typename BatchGroup<T>::Weld& weld, const BatchWork<T>& w, Lanes<T>* p, Lanes<T>* Q) {
  Lanes<T> d[3];
  lane_math::mat_vec(&w.R[9 * weld.link], weld.p, d);
  for (int m = 0; m < 3; ++m) p[m] = w.p[3 * weld.link + m] + d[m];
  lane_math::quat_mul(&w.Q[4 * weld.link], weld.q, Q);
}

// ---- the stages of block b (one file each)

// Dynamics: FK, bias, H and its factor (where step.refactor or the group has none), the unconstrained
// velocity into w.qd (rotational dofs damped) with w.q the coordinates; written to step.qd unless
// `carry_on` (a stage of this block follows in the pass); `inputs` the unit's notes of its wrenches, drives and
// actuators. With qdd, M^-1 (tau - bias ...) itself is written
// there instead of any velocity (forward dynamics)
template <typename T>
void block_dynamics(BatchGroup<T>& G, int b, const BlockKinematics<T>& kin, const StepContext& step,
                    const UnitInputs& inputs, BatchWork<T>& w, bool carry_on, Scalar* qdd = nullptr);

// Rows: the block's joint-limit rows and its worlds' listed contacts, swept by batch_pgs_solve, in the
// lanes of worlds whose rows are not the islands'; w.qd updated, impulses kept. `carried`: w.q and w.qd
// hold this pass's coordinates and velocities (else read from step.in and step.qd); unless `carry_on` the
// velocities are written to step.qd
template <typename T>
void block_rows(const BatchGroup<T>& G, int b, const BlockKinematics<T>& kin, const StepContext& step, BatchWork<T>& w,
                RowWork<T>& R, bool carried, bool carry_on, RowPhaseSeconds* phases);

// Integrate: w.q_next from w.q and w.qd (gathered unless `carried`), the guard's test into step.diverged.
// With `store` the coordinates and velocities go to out.joint_q and out.joint_qd for the worlds that did
// not diverge and whose factor did not fail (the lanes returned), else to step.q_next and step.qd
template <typename T>
IntLanes<T> block_integrate(const BatchGroup<T>& G, int b, const StepContext& step, BatchWork<T>& w, bool carried,
                            bool store);

// Store: body_q and body_qd of the worlds in `written`, from the coordinates q and the velocities w.qd
// (the kinematics in w, o in `o`); with `stream`, a block whose worlds' bodies follow each other, all
// written, goes around the caches
template <typename T>
void block_store(const BatchGroup<T>& G, int b, BatchWork<T>& w, Lanes<T>* o, const Lanes<T>* q,
                 const IntLanes<T>& written, State& out, bool stream);

}  // namespace novaphy
