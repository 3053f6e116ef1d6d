// What every constraint row reads of the solver's settings (the row parts: engine/solver/parts/rows.h).
#pragma once

#include "kernels/pgs.h"

namespace novaphy {

struct RowParams {
  PgsSettings pgs;  // the sweeps: iterations, cfm, friction cone, tolerance
  Scalar erp = 0.2, linear_slop = 0.001, warmstarting_factor = 0.85, restitution_threshold = 0.2;
  bool use_warmstarting = true;
};

}  // namespace novaphy
