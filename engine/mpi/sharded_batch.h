// A batch of worlds sharded over the ranks of an MPI communicator (built with NOVAPHY_WITH_MPI).
// Each rank owns a contiguous range of the global worlds (shard_range), builds and steps only those
// with the local OpenMP engine, and exchanges per-world arrays (observations, actions, flags) with
// collective calls. A world steps exactly as it would in one process: the results are bit-identical.
//
// Every member that communicates is collective: all ranks of the communicator call it in the same order.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "engine/mpi/shard.h"
#include "engine/solver/solver_featherstone.h"

namespace novaphy {

class ShardedBatch {
 public:
  // collective; every rank passes the same world_count (at least one world per rank) and builds
  // worlds alike (see build_worlds); throws Error on every rank if a rank fails to build its share
  // or the worlds differ in layout
  ShardedBatch(MPI_Comm comm, int world_count, const ModelBuilder& shared, const WorldBuilder& build_world,
               const SolverFeatherstoneSettings& settings = {});

  int rank() const { return rank_; }
  int size() const { return size_; }
  int world_count() const { return world_count_; }  // global
  WorldRange range() const { return shard_range(world_count_, rank_, size_); }
  const WorldLayout& layout() const { return layout_; }  // entries per world

  // this rank's worlds
  const Model& model() const { return model_; }
  State& state() { return state_; }
  Control& control() { return control_; }
  Contacts& contacts() { return contacts_; }
  SolverFeatherstone& solver() { return *solver_; }

  // collide and step every local world by dt; collective: if a rank fails, every rank throws Error
  // (naming the rank and its message) and no rank writes its state
  void step(Scalar dt);
  // seconds this rank spent colliding and solving in the last step, without waiting for the others
  double local_step_seconds() const { return local_step_seconds_; }

  // per world: 1 where the last step's divergence guard fired on one of its articulations
  std::vector<std::uint8_t> diverged() const;

  // per-world arrays, world-major: `local` holds this rank's worlds (range().count() * width values),
  // `global` all worlds (world_count() * width) and is read or written on `root` only (ignored
  // elsewhere); width is local.size() / range().count() and must be the same on every rank
  template <typename T>
  void gather(std::span<const T> local, std::span<T> global, int root = 0) const;
  template <typename T>
  void scatter(std::span<const T> global, std::span<T> local, int root = 0) const;
  // every rank receives all worlds
  template <typename T>
  void all_gather(std::span<const T> local, std::span<T> global) const;

 private:
  template <typename T>
  int width_of(std::span<const T> local, const char* what) const;
  // collective: fails on every rank unless root is a rank and the global array (where `applies`)
  // holds world_count * width values
  void check_global(bool applies, size_t size, int width, int root, const char* what) const;
  void counts_of(int width, std::vector<int>& counts, std::vector<int>& displs) const;
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1, world_count_ = 0;
  double local_step_seconds_ = 0;
  Model model_;
  WorldLayout layout_;
  State state_, next_;
  Control control_;
  // made once the model is agreed on every rank
  std::optional<CollisionPipeline> pipeline_;
  Contacts contacts_;
  std::optional<SolverFeatherstone> solver_;
};

}  // namespace novaphy
