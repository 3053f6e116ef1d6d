// Pieces the benchmark programs share: an MJCF robot replicated into many worlds, and how high the
// replicated robots' floating bases stand (whether the floor scenes' robots still stand).
#pragma once

#include "engine/import/mjcf_import.h"
#include "engine/model/model.h"

namespace novaphy {

// the robot in the MJCF file at `path` replicated into `worlds` worlds in `precision`, under the file's
// gravity; with `static_shapes`, its shapes on no body (a floor) kept
inline Model replicated_mjcf(const char* path, int worlds, Precision precision, bool static_shapes) {
  ModelBuilder robot, batch;
  ImportOptions options;
  options.static_shapes = static_shapes;
  import_mjcf(robot, path, options);
  batch.set_gravity(robot.gravity());
  batch.set_precision(precision);
  batch.replicate(robot, worlds);
  return batch.finalize();
}

// the mean over articulations of the third coordinate of each one's first joint (a free base's height,
// +Z up as the MJCF scenes are)
inline double mean_base_height(const Model& model, const State& state) {
  double z = 0;
  for (int a = 0; a < model.articulation_count; ++a) z += state.joint_q[model.articulation(a).q_begin() + 2];
  return z / model.articulation_count;
}

}  // namespace novaphy
