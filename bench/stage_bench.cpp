// Where a step's time goes, per scene, and what unused features cost: collide plus each solver stage
// (settings.profile_stages) as microseconds per step, and a scene against the same scene carrying
// features it does not use.
//   novaphy_bench_stage --benchmark_format=json
// BM_Stages arguments: scene (0 chain15, 1 quadruped without a floor, 2 quadruped standing,
// 3 the 100-robot grid). BM_UnusedFeatures arguments: 0 the 15-link chain, 1 the same chain with a
// visual-only shape on every link (collision group 0), which the broad phase never sees, 2 with a
// small body bolted to every link by a Fixed joint (welded into the link), 3 the same not welded.
// BM_Margin argument: the collision margin in mm. BM_RandomisedParams arguments: randomised (0 every world
// the same robot, 1 every world's masses and inertias its own), precision (0 float64, 1 float32).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>

#include "bench/bench_scenes.h"
#include "engine/import/mjcf_import.h"
#include "engine/mpi/shard.h"
#include "engine/solver/solver_featherstone.h"
#include "tools/robot_grid.h"

namespace novaphy {
namespace {

Model scene(int index) {
  if (index == 3) return build_worlds(grid_ground(), robot_grid(NOVAPHY_SCENE_DIR "/quadruped.xml", 10, 0), {0, 100});
  ModelBuilder builder;
  ImportOptions options;
  options.static_shapes = index == 2;
  import_mjcf(builder, index == 0 ? NOVAPHY_SCENE_DIR "/chain15.xml" : NOVAPHY_SCENE_DIR "/quadruped.xml", options);
  return builder.finalize();
}

void BM_Stages(benchmark::State& bm) {
  const Model model = scene(static_cast<int>(bm.range(0)));
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_threads = 1;
  settings.profile_stages = true;
  SolverFeatherstone solver(model, settings);
  State state = model.state();
  const Control control = model.control();
  for (int k = 0; k < 50; ++k) {  // settle
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  }
  solver.reset_stage_seconds();
  double collide = 0;
  for (auto _ : bm) {
    const auto t0 = std::chrono::steady_clock::now();
    pipeline.collide(state, contacts);
    collide += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    solver.step(state, state, control, contacts, 0.005);
  }
  const SolverStageSeconds& t = solver.stage_seconds();
  const double per_step = 1e6 / std::max(1, t.steps);
  bm.counters["collide_us"] = collide * per_step;
  bm.counters["dynamics_us"] = t.dynamics * per_step;
  bm.counters["limit_rows_us"] = t.limit_rows * per_step;
  bm.counters["contact_rows_us"] = t.contact_rows * per_step;
  bm.counters["solve_us"] = t.solve * per_step;
  bm.counters["integrate_us"] = t.integrate * per_step;
  bm.counters["contacts"] = contacts.contact_count;
}

void BM_UnusedFeatures(benchmark::State& bm) {
  ModelBuilder builder;
  ImportOptions options;
  options.static_shapes = false;
  import_mjcf(builder, NOVAPHY_SCENE_DIR "/chain15.xml", options);
  const int variant = static_cast<int>(bm.range(0));
  const int links = builder.body_count();
  if (variant == 1) {
    ShapeOptions visual;
    visual.collision_group = 0;  // drawn, never collided
    for (int b = 0; b < links; ++b) builder.add_shape_sphere(b, 0.01, visual);
  }
  if (variant >= 2) {
    JointOptions bolted;
    bolted.parent_xform.p = Vec3(0.1, 0.03, 0);
    for (int b = 0; b < links; ++b)
      builder.add_joint_fixed(b, builder.add_body(RigidBody::from_sphere(0.01, 0.01)), bolted);
  }
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_threads = 1;
  settings.weld_fixed_joints = variant != 3;
  SolverFeatherstone solver(model, settings);
  State state = model.state();
  const Control control = model.control();
  for (auto _ : bm) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  }
  const char* labels[] = {"chain15", "chain15 + a visual-only shape per link", "chain15 + a Fixed sensor per link",
                          "chain15 + a Fixed sensor per link, not welded"};
  bm.SetLabel(labels[variant]);
}

// items per second and the counter us_per_world: `seconds` spent in the benchmark's loop, `worlds` a step
void count_worlds(benchmark::State& bm, double seconds, int worlds) {
  bm.SetItemsProcessed(bm.iterations() * worlds);
  bm.counters["us_per_world"] = 1e6 * seconds / (static_cast<double>(bm.iterations()) * worlds);
}

// what the collision margin costs: collide + step of 4096 float32 standing quadrupeds on one thread,
// pgs_tolerance 1e-5, at the margin in mm (the argument); counters: microseconds a world, contacts a
// world and the robots' mean base height after the run
void BM_Margin(benchmark::State& bm) {
  constexpr int kWorlds = 4096;
  const Model model = replicated_mjcf(NOVAPHY_SCENE_DIR "/quadruped.xml", kWorlds, Precision::Float32, true);
  CollisionOptions collision;
  collision.margin = 1e-3 * static_cast<Scalar>(bm.range(0));
  collision.num_threads = 1;
  CollisionPipeline pipeline(model, collision);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_threads = 1;
  settings.pgs_tolerance = 1e-5;
  SolverFeatherstone solver(model, settings);
  State state = model.state();
  const Control control = model.control();
  auto step = [&] {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  };
  for (int k = 0; k < 100; ++k) step();  // onto the floor
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : bm) step();
  count_worlds(bm, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), kWorlds);
  bm.counters["contacts_per_world"] = static_cast<double>(contacts.contact_count) / kWorlds;
  bm.counters["base_height"] = mean_base_height(model, state);
}

// what domain randomisation costs: a step of 4096 contact-free quadrupeds on one thread, every world alike
// (the blocks share one copy of the parameters, which stays in cache) or each world's masses and inertias
// scaled by its own factor in [0.6, 1.4] (a copy per block, read from memory each step); counters:
// microseconds a world and the bytes the solver holds
void BM_RandomisedParams(benchmark::State& bm) {
  constexpr int kWorlds = 4096;
  const bool randomised = bm.range(0) == 1;
  Model model = replicated_mjcf(NOVAPHY_SCENE_DIR "/quadruped.xml", kWorlds,
                                bm.range(1) == 1 ? Precision::Float32 : Precision::Float64, false);
  const int bodies = model.body_count / kWorlds;  // a world's
  if (randomised) {
    for (int b = 0; b < model.body_count; ++b) {
      const Scalar scale = 1 + 0.4 * std::sin(1.7 * (b / bodies));
      model.body_mass[b] *= scale;
      for (int k = 0; k < 9; ++k) model.body_inertia[9 * b + k] *= scale;
    }
  }
  SolverFeatherstoneSettings settings;
  settings.num_threads = 1;
  SolverFeatherstone solver(model, settings);
  Contacts contacts = CollisionPipeline(model).contacts();
  State state = model.state();
  const Control control = model.control();
  for (int k = 0; k < 20; ++k) solver.step(state, state, control, contacts, 0.005);
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : bm) solver.step(state, state, control, contacts, 0.005);
  count_worlds(bm, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), kWorlds);
  bm.counters["solver_bytes"] = static_cast<double>(solver.memory_bytes());
}

BENCHMARK(BM_Stages)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_UnusedFeatures)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Margin)->Arg(10)->Arg(4)->Arg(2)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RandomisedParams)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->ArgNames({"randomised", "precision"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
