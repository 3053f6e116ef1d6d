// The batched kernels, one algorithm per file under kernels/batch/: one articulation topology, one world
// per SIMD lane, in float or double from one templated code path; each has a scalar reference twin
// (kernels/fk, rnea, crba, cholesky, integrate, pgs) that tests/kernels compare it against.
#pragma once

#include "kernels/batch/crba.h"
#include "kernels/batch/factor.h"
#include "kernels/batch/fk.h"
#include "kernels/batch/integrate.h"
#include "kernels/batch/rnea.h"
#include "kernels/batch/topology.h"
