#include "engine/solver/step_arguments.h"

#include <cmath>

#include "engine/model/error.h"

namespace novaphy {

void check_step_arguments(const Model& model, const State& in, const State& out, const Control& control,
                          const Contacts& contacts, Scalar dt) {
  if (!(dt > 0) || !std::isfinite(dt)) fail("dt must be finite and > 0, got ", dt);
  model.check(in);
  model.check(out);
  model.check(control);
  if (!same_layout(contacts, model) || contacts.model_id != model.model_id)
    fail("contacts buffer is from another model (", contacts.body_count, " bodies, ", contacts.shape_count,
         " shapes; the model has ", model.body_count, " and ", model.shape_count, ")");
}

}  // namespace novaphy
