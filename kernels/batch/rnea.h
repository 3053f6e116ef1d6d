// Batched RNEA with zero acceleration (twin: kernels/rnea): the bias forces, a world per lane.
#pragma once

#include "kernels/batch/topology.h"

namespace novaphy {

// link spatial inertias about o, world axes, into w.I
template <typename T>
void batch_link_inertia(const BatchTopology<T>& topo, const BatchParams<T>& params, const Lanes<T>* o, BatchWork<T>& w);

// RNEA with qdd = 0: tau [dof] = bias forces (gravity a_g [3] world, Coriolis, centrifugal) minus the
// applied wrenches f_ext [link][6] about o (nullptr: none); needs batch_velocity and batch_link_inertia
template <typename T>
void batch_bias(const BatchTopology<T>& topo, const Lanes<T>* S, const Lanes<T>* gravity, const Lanes<T>* f_ext,
                BatchWork<T>& w, Lanes<T>* tau);

}  // namespace novaphy
