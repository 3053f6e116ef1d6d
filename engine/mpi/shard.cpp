#include "engine/mpi/shard.h"

#include <algorithm>
#include <vector>

#include "engine/model/error.h"

namespace novaphy {

WorldRange shard_range(int world_count, int rank, int size) {
  if (size < 1) fail("shard_range: size must be >= 1, got ", size);
  if (rank < 0 || rank >= size) fail("shard_range: rank must be in [0, ", size, "), got ", rank);
  if (world_count < 0) fail("shard_range: world_count must be >= 0, got ", world_count);
  const int base = world_count / size, extra = world_count % size;
  WorldRange range;
  range.begin = rank * base + std::min(rank, extra);
  range.end = range.begin + base + (rank < extra ? 1 : 0);
  return range;
}

Model build_worlds(const ModelBuilder& shared, const WorldBuilder& build_world, WorldRange range) {
  if (shared.body_count() > 0)
    fail("build_worlds: the shared builder holds ", shared.body_count(),
         " bodies; it may hold only static shapes (bodies belong to a world)");
  if (range.begin < 0 || range.end < range.begin)
    fail("build_worlds: invalid world range [", range.begin, ", ", range.end, ")");
  ModelBuilder builder = shared;
  for (int w = range.begin; w < range.end; ++w) {
    ModelBuilder world;
    build_world(world, w);
    builder.add_builder(world);
  }
  return builder.finalize();
}

namespace {

// entries per world, given each entry's world in entry order; fails unless the worlds run
// 0, 0, ..., 1, 1, ... in equal blocks
int per_world(const char* entities, const std::vector<int>& world_of, int world_count) {
  std::vector<int> count(world_count, 0);
  for (size_t i = 0; i < world_of.size(); ++i) {
    const int w = world_of[i];
    if (w < 0 || w >= world_count || (i > 0 && w < world_of[i - 1]))
      fail("world_layout: ", entities, " entry ", i, " (world ", w, ") breaks the world-major order");
    ++count[w];
  }
  for (int w = 1; w < world_count; ++w)
    if (count[w] != count[0])
      fail("world_layout: world ", w, " has ", count[w], " ", entities, ", world 0 has ", count[0]);
  return world_count > 0 ? count[0] : 0;
}

}  // namespace

WorldLayout world_layout(const Model& model) {
  WorldLayout layout;
  layout.world_count = model.world_count;
  const auto joint_world = [&](int j) { return model.body_world[model.joint_child[j]]; };
  std::vector<int> coords, dofs, articulations, actuators;
  for (int j = 0; j < model.joint_count; ++j) {
    coords.insert(coords.end(), model.joint_q_start[j + 1] - model.joint_q_start[j], joint_world(j));
    dofs.insert(dofs.end(), model.joint_qd_start[j + 1] - model.joint_qd_start[j], joint_world(j));
  }
  for (int a = 0; a < model.articulation_count; ++a) articulations.push_back(joint_world(model.articulation_start[a]));
  for (int m = 0; m < model.actuator_count; ++m) {
    const int j = model.actuator_joint[m], body = model.actuator_body[m];
    actuators.push_back(j >= 0      ? joint_world(j)
                        : body >= 0 ? model.body_world[body]
                                    : model.tendon_world(model.actuator_tendon[m]));
  }
  layout.body_count = per_world("bodies", model.body_world, model.world_count);
  layout.joint_coord_count = per_world("coordinates", coords, model.world_count);
  layout.joint_dof_count = per_world("dofs", dofs, model.world_count);
  layout.articulation_count = per_world("articulations", articulations, model.world_count);
  layout.actuator_count = per_world("actuators", actuators, model.world_count);
  return layout;
}

}  // namespace novaphy
