#include "engine/mpi/sharded_batch.h"

#include <string>

#include "engine/model/error.h"

namespace novaphy {

namespace {

template <typename T>
MPI_Datatype mpi_type();
template <>
MPI_Datatype mpi_type<double>() {
  return MPI_DOUBLE;
}
template <>
MPI_Datatype mpi_type<float>() {
  return MPI_FLOAT;
}
template <>
MPI_Datatype mpi_type<int>() {
  return MPI_INT;
}
template <>
MPI_Datatype mpi_type<std::uint8_t>() {
  return MPI_UINT8_T;
}

// collective: throws Error on every rank when `error` is non-empty on any, with the message of
// the lowest such rank
void agree(MPI_Comm comm, const std::string& error) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int mine = error.empty() ? size : rank;
  int first = size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == size) return;
  int length = static_cast<int>(error.size());
  MPI_Bcast(&length, 1, MPI_INT, first, comm);
  std::string message = error;
  message.resize(length);
  MPI_Bcast(message.data(), length, MPI_CHAR, first, comm);
  fail("rank ", first, ": ", message);
}

// runs f on this rank and agrees on its failure with every rank
template <typename F>
void collectively(MPI_Comm comm, F&& f) {
  std::string error;
  try {
    f();
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "unknown error";
  }
  agree(comm, error);
}

int comm_rank(MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

int comm_size(MPI_Comm comm) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  return size;
}

Model build_shard(MPI_Comm comm, int world_count, const ModelBuilder& shared, const WorldBuilder& build_world) {
  Model model;
  collectively(comm, [&] {
    if (world_count < comm_size(comm))
      fail("ShardedBatch: world_count must be at least the number of ranks (", comm_size(comm), "), got ", world_count);
    model = build_worlds(shared, build_world, shard_range(world_count, comm_rank(comm), comm_size(comm)));
  });
  return model;
}

}  // namespace

ShardedBatch::ShardedBatch(MPI_Comm comm, int world_count, const ModelBuilder& shared, const WorldBuilder& build_world,
                           const SolverFeatherstoneSettings& settings)
    : comm_(comm),
      rank_(comm_rank(comm)),
      size_(comm_size(comm)),
      world_count_(world_count),
      model_(build_shard(comm, world_count, shared, build_world)),
      state_(model_.state()),
      next_(state_),
      control_(model_.control()) {
  // every rank's worlds have one layout, or per-world arrays would not line up
  collectively(comm_, [&] {
    if (model_.world_count != range().count())
      fail("ShardedBatch: the world builder made ", model_.world_count, " worlds for ", range().count(),
           " calls (it must add bodies to the builder it is given, each call one world)");
    layout_ = world_layout(model_);
    pipeline_.emplace(model_);
    contacts_ = pipeline_->contacts();
    solver_.emplace(model_, settings);
  });
  const int mine[5] = {layout_.body_count, layout_.joint_coord_count, layout_.joint_dof_count,
                       layout_.articulation_count, layout_.actuator_count};
  int low[5], high[5];
  MPI_Allreduce(mine, low, 5, MPI_INT, MPI_MIN, comm_);
  MPI_Allreduce(mine, high, 5, MPI_INT, MPI_MAX, comm_);
  const char* names[5] = {"bodies", "coordinates", "dofs", "articulations", "actuators"};
  for (int k = 0; k < 5; ++k)
    if (low[k] != high[k])
      fail("ShardedBatch: worlds differ between ranks: ", low[k], " to ", high[k], " ", names[k], " per world");
}

void ShardedBatch::step(Scalar dt) {
  collectively(comm_, [&] {
    const double start = MPI_Wtime();
    pipeline_->collide(state_, contacts_);
    solver_->step(state_, next_, control_, contacts_, dt);
    local_step_seconds_ = MPI_Wtime() - start;
  });
  state_.assign(next_);
}

std::vector<std::uint8_t> ShardedBatch::diverged() const {
  std::vector<std::uint8_t> flags(range().count(), 0);
  const std::vector<std::uint8_t>& art = solver_->diverged();
  for (size_t a = 0; a < art.size(); ++a)
    if (art[a]) flags[a / layout_.articulation_count] = 1;
  return flags;
}

template <typename T>
int ShardedBatch::width_of(std::span<const T> local, const char* what) const {
  const int count = range().count();
  std::string error;
  if (count > 0 && local.size() % count != 0)
    error = std::string(what) + ": " + std::to_string(local.size()) + " local values do not split into " +
            std::to_string(count) + " worlds";
  else if (count == 0 && !local.empty())
    error = std::string(what) + ": " + std::to_string(local.size()) + " local values on a rank without worlds";
  agree(comm_, error);
  const int mine = count > 0 ? static_cast<int>(local.size()) / count : -1;
  int low = 0, high = 0;
  MPI_Allreduce(&mine, &high, 1, MPI_INT, MPI_MAX, comm_);
  const int other = mine < 0 ? high : mine;
  MPI_Allreduce(&other, &low, 1, MPI_INT, MPI_MIN, comm_);
  if (low != high) fail(what, ": values per world differ between ranks (", low, " to ", high, ")");
  return high < 0 ? 0 : high;
}

void ShardedBatch::check_global(bool applies, size_t size, int width, int root, const char* what) const {
  std::string error;
  if (root < 0 || root >= size_)
    error = std::string(what) + ": root must be in [0, " + std::to_string(size_) + "), got " + std::to_string(root);
  else if (applies && size != static_cast<size_t>(world_count_) * width)
    error = std::string(what) + ": the global array holds " + std::to_string(size) + " values, " +
            std::to_string(world_count_) + " worlds need " + std::to_string(world_count_ * width);
  agree(comm_, error);
}

void ShardedBatch::counts_of(int width, std::vector<int>& counts, std::vector<int>& displs) const {
  counts.resize(size_);
  displs.resize(size_);
  for (int r = 0; r < size_; ++r) {
    const WorldRange range = shard_range(world_count_, r, size_);
    counts[r] = range.count() * width;
    displs[r] = range.begin * width;
  }
}

template <typename T>
void ShardedBatch::gather(std::span<const T> local, std::span<T> global, int root) const {
  const int width = width_of(local, "gather");
  check_global(rank_ == root, global.size(), width, root, "gather");
  std::vector<int> counts, displs;
  counts_of(width, counts, displs);
  MPI_Gatherv(local.data(), static_cast<int>(local.size()), mpi_type<T>(), global.data(), counts.data(), displs.data(),
              mpi_type<T>(), root, comm_);
}

template <typename T>
void ShardedBatch::scatter(std::span<const T> global, std::span<T> local, int root) const {
  const int width = width_of(std::span<const T>(local.data(), local.size()), "scatter");
  check_global(rank_ == root, global.size(), width, root, "scatter");
  std::vector<int> counts, displs;
  counts_of(width, counts, displs);
  MPI_Scatterv(global.data(), counts.data(), displs.data(), mpi_type<T>(), local.data(), static_cast<int>(local.size()),
               mpi_type<T>(), root, comm_);
}

template <typename T>
void ShardedBatch::all_gather(std::span<const T> local, std::span<T> global) const {
  const int width = width_of(local, "all_gather");
  check_global(true, global.size(), width, 0, "all_gather");
  std::vector<int> counts, displs;
  counts_of(width, counts, displs);
  MPI_Allgatherv(local.data(), static_cast<int>(local.size()), mpi_type<T>(), global.data(), counts.data(),
                 displs.data(), mpi_type<T>(), comm_);
}

#define NOVAPHY_INSTANTIATE(T)                                                         \
  template void ShardedBatch::gather<T>(std::span<const T>, std::span<T>, int) const;  \
  template void ShardedBatch::scatter<T>(std::span<const T>, std::span<T>, int) const; \
  template void ShardedBatch::all_gather<T>(std::span<const T>, std::span<T>) const;
NOVAPHY_INSTANTIATE(double)
NOVAPHY_INSTANTIATE(float)
NOVAPHY_INSTANTIATE(int)
NOVAPHY_INSTANTIATE(std::uint8_t)
#undef NOVAPHY_INSTANTIATE

}  // namespace novaphy
