// Batched kernels: one articulation topology, one world per SIMD lane (AoSoA: a block holds
// kLanes<T> worlds and every per-world quantity is one Lanes<T> per component). Templated on the
// precision (float or double): one code path for both. Their reference twins are the scalar
// kernels fk, rnea, crba and cholesky; tests/kernels/batch_test.cpp compares them.
// This file: the topology a batch shares, its per-world parameters and a block's scratch.
//
// Spatial quantities here are in world axes about a point o per world (the root link's origin),
// so no Plücker transforms are needed between links: a composite inertia is a sum, H_kj = s_j . (I_k s_k).
// An inertia is kept as 10 numbers (m, h = m c, J = rotational inertia about o); H is packed lower
// triangular and factored H = L^T L in place with the tree's sparsity (Featherstone's LTL, RBDA 6.5):
// entry (k, j) is only touched when dof j is dof k or one of its ancestors, so a quadruped's legs
// cost nothing against each other.
#pragma once

#include <cstdint>
#include <vector>

#include "kernels/articulation.h"
#include "kernels/lanes.h"

namespace novaphy {

// the joints, frames and axes every world of a batch shares, in precision T
template <typename T>
struct BatchTopology {
  struct Link {
    JointType type = JointType::Fixed;
    int parent = -1;
    int q_start = 0, qd_start = 0, dof = 0;
    T P0[4], P1[4];         // rotation in the parent link [x, y, z, w]: Revolute cos(q/2) P0 + sin(q/2) P1, else P0
    T Qp[4], Qci[4];        // rotations of X_p and of X_c^-1 (Ball, Free)
    T Rp[9];                // rotation of X_p, row-major
    T tp[3];                // translation of X_p
    T T0[3], T1[3], T2[3];  // translation in the parent: Revolute T0 + sin q T1 + (1 - cos q) T2, Prismatic T0 + q T1
    T b[3];                 // translation of X_c^-1 (Ball, Free)
    T tc[3];                // origin of the child joint frame in the link
    T Rc[9];                // axes of the child joint frame in the link (rotation of X_c, row-major)
    T ac[3];                // joint axis in link coordinates (Revolute, Prismatic)
  };
  std::vector<Link> link;
  std::vector<int> dof_parent;    // per dof: the next dof up the tree, -1 past the root
  std::vector<int> coord_of_dof;  // per dof: its coordinate for Revolute / Prismatic joints, else -1
  // per dof k: its ancestors ascending, ancestors[ancestor_start[k] .. ancestor_start[k + 1]) (H's
  // nonzeros left of the diagonal in row k), and where row k starts in the packed triangle
  std::vector<int> ancestor_start, ancestors, row_start;
  // per dof j: the dofs it is an ancestor of, descending, descendants[descendant_start[j] .. descendant_start[j +
  // 1]) (H's nonzeros below the diagonal in column j)
  std::vector<int> descendant_start, descendants;
  // the same ancestors as runs of consecutive dofs (a chain's dofs are numbered in a row), per dof k
  // ancestor_runs[run_start[k] .. run_start[k + 1]): the factor and the solves walk a run of a row as
  // one dense stretch, without an index per entry
  struct Run {
    int dof, count;
  };
  std::vector<int> run_start;
  std::vector<Run> ancestor_runs;
  // per link i: the dofs that move it (its ancestors' and its own) ascending, link_dofs[link_dof_start[i] ..
  // link_dof_start[i + 1]): the nonzero columns of its Jacobian, which batch_mass_matrix_gemm multiplies
  std::vector<int> link_dof_start, link_dofs;
  int coord_count = 0;
  int dof_count = 0;

  explicit BatchTopology(const ArticulationView& art);
  int packed_size() const { return dof_count * (dof_count + 1) / 2; }
};

// H's packed lower triangle: entry (i, j), j <= i
inline int packed_index(int i, int j) { return i * (i + 1) / 2 + j; }

// one block's per-world parameters (read from the model when the solver is made, and again for the worlds whose
// parameters change: Model::set_parameter) as a field table,
// X(name, count, doc), `count` over the topology's n links and nv dofs: the fields lie in one buffer of
// batch_param_count lanes in the table's order
#define NOVAPHY_BATCH_PARAMS(X)                                                         \
  X(mass, n, "[link]")                                                                  \
  X(com, 3 * n, "[link][3] body frame")                                                 \
  X(inertia, 6 * n, "[link][6] xx yy zz xy xz yz about the centre of mass, body frame") \
  X(armature, nv, "[dof]")                                                              \
  X(damping, nv, "[dof]")                                                               \
  X(stiffness, nv, "[dof]")                                                             \
  X(q_ref, nv, "[dof] spring rest position (Revolute, Prismatic)")                      \
  X(gravity, 3, "[3] the world's gravity")

template <typename T>
struct BatchParams {
#define NOVAPHY_DECLARE_PARAM(name, count, doc) const Lanes<T>* name;
  NOVAPHY_BATCH_PARAMS(NOVAPHY_DECLARE_PARAM)
#undef NOVAPHY_DECLARE_PARAM
};

// where each field starts in the buffer, and the buffer's size
struct BatchParamOffsets {
#define NOVAPHY_DECLARE_OFFSET(name, count, doc) int name = 0;
  NOVAPHY_BATCH_PARAMS(NOVAPHY_DECLARE_OFFSET)
#undef NOVAPHY_DECLARE_OFFSET
  int count = 0;
};
template <typename T>
BatchParamOffsets batch_param_offsets(const BatchTopology<T>& topo) {
  const int n = static_cast<int>(topo.link.size()), nv = topo.dof_count;
  BatchParamOffsets at;
#define NOVAPHY_PLACE_PARAM(name, count_, doc) \
  at.name = at.count;                          \
  at.count += (count_);
  NOVAPHY_BATCH_PARAMS(NOVAPHY_PLACE_PARAM)
#undef NOVAPHY_PLACE_PARAM
  return at;
}

// BatchParams over one buffer of batch_param_count lanes, and lane `lane` of it filled from an articulation's
// model arrays
template <typename T>
int batch_param_count(const BatchTopology<T>& topo) {
  return batch_param_offsets(topo).count;
}
template <typename T>
BatchParams<T> batch_params(const BatchTopology<T>& topo, const Lanes<T>* data) {
  const BatchParamOffsets at = batch_param_offsets(topo);
  BatchParams<T> P;
#define NOVAPHY_POINT_PARAM(name, count, doc) P.name = data + at.name;
  NOVAPHY_BATCH_PARAMS(NOVAPHY_POINT_PARAM)
#undef NOVAPHY_POINT_PARAM
  return P;
}
template <typename T>
void batch_set_params(const BatchTopology<T>& topo, const ArticulationView& art, int lane, Lanes<T>* data);

// one block's kinematics and per-link work, sized for a topology (a thread's scratch), as a field table,
// X(name, count, doc), `count` over the topology's n links, nc coordinates and nv dofs: resize sizes each field
#define NOVAPHY_BATCH_WORK(X)                                                             \
  X(Q, 4 * n, "[link][4] link orientation in the world")                                  \
  X(p, 3 * n, "[link][3] link position in the world")                                     \
  X(R, 9 * n, "[link][9] link rotation in the world")                                     \
  X(v, 6 * n, "[link][6] velocity about o")                                               \
  X(a, 6 * n, "[link][6] acceleration about o")                                           \
  X(f, 6 * n, "[link][6] force about o")                                                  \
  X(I, 10 * n, "[link][10] m, h, J (xx yy zz xy xz yz); composite after the mass matrix") \
  X(vrel, 3 * n, "[link][3] Free joints: linear velocity in the parent, world axes")      \
  X(q, nc, "[coord] a block's coordinates")                                               \
  X(qd, nv, "[dof] its velocities")                                                       \
  X(x, nv, "[dof] a right-hand side")                                                     \
  X(q_next, nc, "[coord] coordinates after the step")                                     \
  X(tau, nv, "[dof] bias forces")                                                         \
  X(diag, nv, "[dof] implicit diagonal added to H")                                       \
  X(f_ext, 6 * n, "[link][6] applied wrenches about o")                                   \
  X(kd, nv, "[dof] PD drive: velocity gain")                                              \
  X(target_vel, nv, "[dof] PD drive: target velocity")                                    \
  X(ke, nv, "[dof] PD drive: position gain")                                              \
  X(target_pos, nv, "[dof] PD drive: target position")                                    \
  X(actuator_stiffness, nv, "[dof] the actuators' stiffness")                             \
  X(actuator_damping, nv, "[dof] the actuators' damping")                                 \
  X(IJ, 6 * (nv + 1), "[column][6] I_i J_i of batch_mass_matrix_gemm, then a zero column")

template <typename T>
struct BatchWork {
#define NOVAPHY_DECLARE_WORK(name, count, doc) std::vector<Lanes<T>> name;
  NOVAPHY_BATCH_WORK(NOVAPHY_DECLARE_WORK)
#undef NOVAPHY_DECLARE_WORK
  std::vector<Lanes<T>> bodies;  // [body][13] body_q and body_qd on their way out (sized by the owner)

  void resize(const BatchTopology<T>& topo);
  std::size_t bytes() const;  // (bodies included)
};

}  // namespace novaphy
