#include "engine/solver/simulate.h"

#include <cmath>

#include "engine/model/error.h"

namespace novaphy {

void simulate(CollisionPipeline& pipeline, SolverFeatherstone& solver, State& state, const Control& control,
              Contacts& contacts, int substeps, Scalar dt) {
  if (substeps < 1) fail("simulate: substeps must be >= 1, got ", substeps);
  if (!(dt >= 0) || !std::isfinite(dt))
    fail("simulate: dt must be finite and >= 0 (0: the model's timestep), got ", dt);
  const Scalar step = dt > 0 ? dt : solver.model().timestep;
  for (int k = 0; k < substeps; ++k) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, step);
  }
}

}  // namespace novaphy
