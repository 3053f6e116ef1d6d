// The MPI batch runner: the 100-robot grid (floating quadrupeds on one ground plane) scaled to N
// worlds, sharded over the ranks of MPI_COMM_WORLD, stepped T times. Every step the root scatters
// actions (joint_f) and gathers observations (joint_q, joint_qd) and divergence flags, as a
// learning loop would. Prints global robot-steps/s and each rank's share of the time.
//   mpirun -np 2 novaphy_mpi_run [--worlds N] [--steps T] [--dt s] [--threads k] [--scene file.xml]
//                               [--no-exchange] [--no-progress] [--output file]
// --output writes the final joint_q and joint_qd of all worlds (raw doubles) for comparison.
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "engine/model/error.h"
#include "engine/mpi/sharded_batch.h"
#include "tools/progress.h"
#include "tools/robot_grid.h"

namespace {

struct Options {
  int worlds = 100;
  int steps = 1000;
  double dt = 0.005;
  int threads = 0;
  std::string scene = NOVAPHY_SCENE_DIR "/quadruped.xml";
  bool exchange = true;
  bool progress = true;
  std::string output;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const bool has_value = k + 1 < argc;
    if (arg == "--worlds" && has_value)
      o.worlds = std::atoi(argv[++k]);
    else if (arg == "--steps" && has_value)
      o.steps = std::atoi(argv[++k]);
    else if (arg == "--dt" && has_value)
      o.dt = std::atof(argv[++k]);
    else if (arg == "--threads" && has_value)
      o.threads = std::atoi(argv[++k]);
    else if (arg == "--scene" && has_value)
      o.scene = argv[++k];
    else if (arg == "--output" && has_value)
      o.output = argv[++k];
    else if (arg == "--no-exchange")
      o.exchange = false;
    else if (arg == "--no-progress")
      o.progress = false;
    else
      novaphy::fail("novaphy_mpi_run: unknown argument '", arg, "'");
  }
  if (o.steps < 0) novaphy::fail("novaphy_mpi_run: --steps must be >= 0, got ", o.steps);
  return o;
}

int run(const Options& o) {
  // world w: the scene's robot at its place in a square grid, 0.3 m above the ground
  const int side = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(o.worlds)))));
  novaphy::SolverFeatherstoneSettings settings;
  settings.num_threads = o.threads;
  novaphy::ShardedBatch batch(MPI_COMM_WORLD, o.worlds, novaphy::grid_ground(), novaphy::robot_grid(o.scene, side, 0.3),
                              settings);
  const novaphy::WorldRange range = batch.range();
  const novaphy::WorldLayout& layout = batch.layout();
  const int nq = layout.joint_coord_count, nv = layout.joint_dof_count;
  const bool root = batch.rank() == 0;

  // the root's global arrays: actions in, observations and flags out
  std::vector<double> actions(root ? o.worlds * nv : 0), q(root ? o.worlds * nq : 0), qd(root ? o.worlds * nv : 0);
  std::vector<std::uint8_t> flags(root ? o.worlds : 0);
  double step_seconds = 0, exchange_seconds = 0;
  long diverged = 0;
  novaphy::ProgressBar bar(o.steps, "steps", o.progress && root);
  MPI_Barrier(MPI_COMM_WORLD);
  const double start = MPI_Wtime();
  for (int s = 0; s < o.steps; ++s) {
    const double t0 = MPI_Wtime();
    if (o.exchange) {
      for (size_t i = 0; i < actions.size(); ++i) actions[i] = 2 * std::sin(o.dt * s + 0.1 * i);
      batch.scatter<double>(actions, batch.control().joint_f);
    }
    const double t1 = MPI_Wtime();
    batch.step(o.dt);
    const double t2 = MPI_Wtime();
    step_seconds += batch.local_step_seconds();
    if (o.exchange) {
      batch.gather<double>(batch.state().joint_q, q);
      batch.gather<double>(batch.state().joint_qd, qd);
      batch.gather<std::uint8_t>(batch.diverged(), flags);
      for (std::uint8_t f : flags) diverged += f;
    }
    exchange_seconds += (t1 - t0) + (MPI_Wtime() - t2);
    bar.update(s + 1);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const double wall = MPI_Wtime() - start;

  // per rank: worlds, stepping and exchange seconds
  const double mine[3] = {static_cast<double>(range.count()), step_seconds, exchange_seconds};
  std::vector<double> all(3 * batch.size());
  MPI_Gather(mine, 3, MPI_DOUBLE, all.data(), 3, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  std::vector<double> final_q(root ? o.worlds * nq : 0), final_qd(root ? o.worlds * nv : 0);
  batch.gather<double>(batch.state().joint_q, final_q);
  batch.gather<double>(batch.state().joint_qd, final_qd);
  if (!root) return 0;

  double slowest = 0, mean = 0;
  for (int r = 0; r < batch.size(); ++r) {
    slowest = std::max(slowest, all[3 * r + 1]);
    mean += all[3 * r + 1] / batch.size();
  }
  std::printf("novaphy_mpi_run: %d worlds (%d coordinates, %d dofs each), %d steps of %g s, %d ranks\n", o.worlds, nq,
              nv, o.steps, o.dt, batch.size());
  // step (s): this rank's own collide and solve time, without waiting for the others
  std::printf("%5s %7s %10s %11s %9s\n", "rank", "worlds", "step (s)", "exchange(s)", "load");
  for (int r = 0; r < batch.size(); ++r)
    std::printf("%5d %7.0f %10.3f %11.3f %9.3f\n", r, all[3 * r], all[3 * r + 1], all[3 * r + 2],
                mean > 0 ? all[3 * r + 1] / mean : 1.0);
  const double bytes = o.exchange ? o.worlds * (8.0 * (nq + 2 * nv) + 1) : 0;
  std::printf("global: %.0f robot-steps/s, wall %.3f s, balance (slowest/mean step time) %.3f\n",
              wall > 0 ? o.worlds * static_cast<double>(o.steps) / wall : 0, wall, mean > 0 ? slowest / mean : 1.0);
  std::printf("exchanged per step: %.0f bytes (%d worlds x (8 (nq + 2 nv) + 1)); worlds flagged diverged: %ld\n", bytes,
              o.worlds, diverged);
  if (!o.output.empty()) {
    std::ofstream out(o.output, std::ios::binary);
    out.write(reinterpret_cast<const char*>(final_q.data()), final_q.size() * sizeof(double));
    out.write(reinterpret_cast<const char*>(final_qd.data()), final_qd.size() * sizeof(double));
    if (!out) novaphy::fail("novaphy_mpi_run: cannot write ", o.output);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int code = 0;
  try {
    code = run(parse(argc, argv));
  } catch (const novaphy::Error& error) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0) std::fprintf(stderr, "%s\n", error.what());
    code = 2;
  }
  MPI_Finalize();
  return code;
}
