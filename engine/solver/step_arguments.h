// What every solver's step checks of its arguments before it reads them.
#pragma once

#include "engine/collision/pipeline.h"
#include "engine/model/model.h"

namespace novaphy {

// throws Error naming the first bad argument: dt not finite or not > 0, a state, control or contacts buffer not of
// `model` (its layout and fingerprint)
void check_step_arguments(const Model& model, const State& in, const State& out, const Control& control,
                          const Contacts& contacts, Scalar dt);

}  // namespace novaphy
