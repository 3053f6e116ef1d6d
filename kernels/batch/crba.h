// Batched mass matrix (twin: kernels/crba): CRBA over composite inertias, or the tiled product
// sum J_i^T I_i J_i, into H packed lower triangular, a world per lane.
#pragma once

#include "kernels/batch/topology.h"

namespace novaphy {

// CRBA: H [packed] with armature; turns w.I into composite inertias
template <typename T>
void batch_mass_matrix(const BatchTopology<T>& topo, const BatchParams<T>& params, const Lanes<T>* S, BatchWork<T>& w,
                       Lanes<T>* H);

// the use_tile_gemm path: H [packed] = sum over links of J_i^T (I_i J_i) with armature, J_i the
// columns of S that move link i, multiplied in register tiles of kGemmTile x kGemmTile entries of H
// (a link's columns padded with a zero column to whole tiles); w.I is left as batch_link_inertia made it
constexpr int kGemmTile = 4;
template <typename T>
void batch_mass_matrix_gemm(const BatchTopology<T>& topo, const BatchParams<T>& params, const Lanes<T>* S,
                            BatchWork<T>& w, Lanes<T>* H);

}  // namespace novaphy
