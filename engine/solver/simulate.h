// The loop a learning environment runs between two actions, in one call: `substeps` times a collide at the state's
// poses, then a step of dt. From Python it runs without the GIL (novaphy.simulate).
#pragma once

#include "engine/collision/pipeline.h"
#include "engine/solver/solver_featherstone.h"

namespace novaphy {

// `substeps` steps of dt (0: the model's timestep, MJCF's <option timestep>) of `state`, in place, under `control`:
// each a pipeline.collide into `contacts`, then a solver.step, exactly as that loop written out (the same bits).
// Throws Error for substeps < 1 or a dt below 0 or not finite before anything is stepped; what collide and step
// throw (a state of another model, a divergence under Raise) stops the loop after the substeps before it
void simulate(CollisionPipeline& pipeline, SolverFeatherstone& solver, State& state, const Control& control,
              Contacts& contacts, int substeps, Scalar dt = 0);

}  // namespace novaphy
