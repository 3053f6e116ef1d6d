// The 100-robot grid's pieces, shared by the MPI runner, the sweep, the benchmarks and the tests: a
// ground plane every world collides with (+Z up, as the MJCF scenes are) and world w = the file's
// robot at its place in a square grid of `side` columns 1.5 m apart, `drop` metres above its pose in
// the file, without the file's own floor.
#pragma once

#include <string>

#include "engine/import/mjcf_import.h"
#include "engine/mpi/shard.h"

namespace novaphy {

inline ModelBuilder grid_ground() {
  ModelBuilder shared(Vec3(0, 0, -9.81));
  shared.add_plane(Vec3(0, 0, 1), 0);
  return shared;
}

inline WorldBuilder robot_grid(const std::string& path, int side, Scalar drop) {
  return [path, side, drop](ModelBuilder& builder, int w) {
    ImportOptions options;
    options.xform.p = Vec3(1.5 * (w % side), 1.5 * (w / side), drop);
    options.static_shapes = false;
    import_mjcf(builder, path, options);
  };
}

}  // namespace novaphy
