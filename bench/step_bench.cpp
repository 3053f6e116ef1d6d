// Whole steps of many robots: NovaPhy's SolverFeatherstone on replicated worlds beside MuJoCo 2.2.2
// stepping one mjData per world in the same OpenMP loop, same MJCF, same dt, same process.
//   novaphy_bench_step --benchmark_format=json
// Arguments: scene (0 chain15, 1 quadruped without a floor, 2 quadruped standing), worlds, threads.
// items_per_second is robot-steps per second.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <memory>
#include <vector>

#include "engine/mjcf_import.h"
#include "engine/solver_featherstone.h"

namespace novaphy {
namespace {

struct SceneSpec {
  const char* path;
  bool floor;
};
const SceneSpec kScenes[] = {{NOVAPHY_SCENE_DIR "/chain15.xml", false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", true}};

void label(benchmark::State& bm, int worlds) {
  bm.SetItemsProcessed(bm.iterations() * worlds);
  bm.counters["worlds"] = worlds;
  bm.counters["threads"] = static_cast<double>(bm.range(2));
}

void BM_NovaPhyStep(benchmark::State& bm) {
  const SceneSpec& spec = kScenes[bm.range(0)];
  const int worlds = static_cast<int>(bm.range(1));
  ModelBuilder robot, batch;
  ImportOptions options;
  options.static_shapes = spec.floor;
  import_mjcf(robot, spec.path, options);
  batch.set_gravity(robot.gravity());
  batch.replicate(robot, worlds);
  const Model model = batch.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_threads = static_cast<int>(bm.range(2));
  SolverFeatherstone solver(model, settings);
  State state = model.state();
  const Control control = model.control();
  for (int k = 0; k < 50; ++k) {  // settle onto the floor before timing
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  }
  for (auto _ : bm) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  }
  label(bm, worlds);
}

void BM_MujocoStep(benchmark::State& bm) {
  const SceneSpec& spec = kScenes[bm.range(0)];
  const int worlds = static_cast<int>(bm.range(1));
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m(load_mujoco_model(spec.path), mj_deleteModel);
  if (!spec.floor) m->opt.disableflags |= mjDSBL_CONTACT;
  m->opt.timestep = 0.005;
  std::vector<mjData*> data(worlds);
  for (auto& d : data) d = mj_makeData(m.get());
  const int threads = static_cast<int>(bm.range(2));
  for (int k = 0; k < 50; ++k)
    for (auto* d : data) mj_step(m.get(), d);
  for (auto _ : bm) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int w = 0; w < worlds; ++w) mj_step(m.get(), data[w]);
  }
  for (auto* d : data) mj_deleteData(d);
  label(bm, worlds);
}

void sweep(benchmark::internal::Benchmark* b) {
  for (int scene = 0; scene < 3; ++scene)
    for (const int worlds : {1, 64, 1024})
      for (const int threads : {1, 2}) b->Args({scene, worlds, threads});
  b->ArgNames({"scene", "worlds", "threads"})->UseRealTime();
}

BENCHMARK(BM_NovaPhyStep)->Apply(sweep);
BENCHMARK(BM_MujocoStep)->Apply(sweep);

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
