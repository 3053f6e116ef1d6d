// Batched forward kinematics (twin: kernels/fk): link poses, motion subspaces in world axes about the
// root origin o, and link velocities, a world per lane.
#pragma once

#include "kernels/batch/topology.h"

namespace novaphy {

// link poses from coordinates q [coord]; o [3] = the root link's origin
template <typename T>
void batch_kinematics(const BatchTopology<T>& topo, const Lanes<T>* q, BatchWork<T>& w, Lanes<T>* o);

// motion subspace S [dof][6] in world axes about o, from batch_kinematics' poses
template <typename T>
void batch_subspace(const BatchTopology<T>& topo, const BatchWork<T>& w, const Lanes<T>* o, Lanes<T>* S);

// link velocities v from qd [dof]; Free joints' relative linear velocity into w.vrel
template <typename T>
void batch_velocity(const BatchTopology<T>& topo, const Lanes<T>* S, const Lanes<T>* qd, BatchWork<T>& w);

// batch_subspace then batch_velocity with each link's columns kept in registers instead of written to S
// (for velocities alone: body_qd at the end of a step); the same operations in the same order, the same bits
template <typename T>
void batch_subspace_velocity(const BatchTopology<T>& topo, const Lanes<T>* o, const Lanes<T>* qd, BatchWork<T>& w);

}  // namespace novaphy
