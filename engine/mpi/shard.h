// Worlds split into shards: which contiguous range of the global worlds a rank owns, and the model
// of such a range. Needs no MPI; engine/mpi/sharded_batch.h builds the MPI batch on it.
#pragma once

#include <functional>

#include "engine/model/builder.h"

namespace novaphy {

struct WorldRange {
  int begin = 0;
  int end = 0;
  int count() const { return end - begin; }
};

// the worlds rank `rank` of `size` owns: contiguous, in rank order, the first world_count % size
// ranks one more than the others; throws Error unless 0 <= rank < size and world_count >= 0
WorldRange shard_range(int world_count, int rank, int size);

// builds the content of global world `world` into an empty builder
using WorldBuilder = std::function<void(ModelBuilder& builder, int world)>;

// `shared` (static shapes every world collides with, such as the ground; no bodies) followed by the
// worlds of `range`, one world each: the same worlds, placed alike, whichever rank builds them
Model build_worlds(const ModelBuilder& shared, const WorldBuilder& build_world, WorldRange range);

// entries per world of a model whose worlds share one layout, each world's entries contiguous
struct WorldLayout {
  int world_count = 0;
  int body_count = 0;
  int joint_coord_count = 0;
  int joint_dof_count = 0;
  int articulation_count = 0;
  int actuator_count = 0;
};
// throws Error naming the first entity whose count or order differs between worlds
WorldLayout world_layout(const Model& model);

}  // namespace novaphy
