// Batched semi-implicit joint integration (twin: kernels/integrate), a world per lane.
#pragma once

#include "kernels/batch/topology.h"

namespace novaphy {

// semi-implicit step of the coordinates: q_out = q (+) dt qd, quaternions by the exponential map
template <typename T>
void batch_integrate(const BatchTopology<T>& topo, const Lanes<T>* q, const Lanes<T>* qd, T dt, Lanes<T>* q_out);

}  // namespace novaphy
