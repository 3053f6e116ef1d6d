// Whole steps of many robots: NovaPhy's SolverFeatherstone on replicated worlds beside MuJoCo 2.2.2
// stepping one mjData per world in the same OpenMP loop, same MJCF, same dt, same process.
//   novaphy_bench_step --benchmark_format=json
// Arguments: scene (0 chain15, 1 quadruped without a floor, 2 quadruped standing, 3 MuJoCo's
// humanoid.xml without contacts, 4 the standing quadruped with settings.pgs_tolerance = 1e-5 m/s,
// NovaPhy only: MuJoCo's reference is scene 2, which already stops its solver at its own tolerance),
// worlds, threads, precision (NovaPhy: 0 float64, 1 float32; MuJoCo is double). items_per_second is
// robot-steps per second. tools/bench_report.py turns the JSON into the README's table.
// The floor scenes collide at margin 0, the MJCF's own (MuJoCo's default geom margin): contacts where shapes
// touch, the same four a robot MuJoCo finds; at the pipeline's default 1 cm the shins' capsule ends, 5 mm
// above the floor, add four speculative contacts a robot (the README gives both speeds)
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
  Scalar pgs_tolerance = 0;
};
const SceneSpec kScenes[] = {{NOVAPHY_SCENE_DIR "/chain15.xml", false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", true},
                             {NOVAPHY_HUMANOID_XML, false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", true, 1e-5}};

void label(benchmark::State& bm, int worlds) {
  bm.SetItemsProcessed(bm.iterations() * worlds);
  bm.counters["scene"] = static_cast<double>(bm.range(0));
  bm.counters["worlds"] = worlds;
  bm.counters["threads"] = static_cast<double>(bm.range(2));
  bm.counters["precision"] = static_cast<double>(bm.range(3));
}

void BM_NovaPhyStep(benchmark::State& bm) {
  const SceneSpec& spec = kScenes[bm.range(0)];
  const int worlds = static_cast<int>(bm.range(1));
  ModelBuilder robot, batch;
  ImportOptions options;
  options.static_shapes = spec.floor;
  import_mjcf(robot, spec.path, options);
  batch.set_gravity(robot.gravity());
  batch.set_precision(bm.range(3) == 1 ? Precision::Float32 : Precision::Float64);
  batch.replicate(robot, worlds);
  const Model model = batch.finalize();
  CollisionOptions collision;
  collision.num_threads = static_cast<int>(bm.range(2));
  collision.margin = 0;
  CollisionPipeline pipeline(model, collision);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.num_threads = static_cast<int>(bm.range(2));
  settings.pgs_tolerance = spec.pgs_tolerance;
  SolverFeatherstone solver(model, settings);
  State state = model.state();
  const Control control = model.control();
  for (int k = 0; k < 50; ++k) {  // settle onto the floor before timing
    if (spec.floor) pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  }
  for (auto _ : bm) {
    if (spec.floor) pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 0.005);
  }
  label(bm, worlds);
  // the floor scenes' robots still standing: their base's mean height (MuJoCo's beside it)
  if (spec.floor) {
    double z = 0;
    for (int a = 0; a < model.articulation_count; ++a) z += state.joint_q[model.articulation(a).q_begin() + 2];
    bm.counters["base_height"] = z / model.articulation_count;
  }
  // memory per world: what the solver holds, the State's arrays, and H with its factor (two packed
  // triangles in the model's precision): the least a world can be stepped in
  bm.counters["solver_bytes_per_world"] = static_cast<double>(solver.memory_bytes()) / worlds;
  const std::size_t state_scalars =
      state.joint_q.size() + state.joint_qd.size() + state.body_q.size() + state.body_qd.size() + state.body_f.size();
  bm.counters["state_bytes_per_world"] = state_scalars * sizeof(Scalar) / static_cast<double>(worlds);
  std::size_t h = 0;
  for (int a = 0; a < model.articulation_count; ++a) {
    const std::size_t n = model.articulation(a).dof_count();
    h += n * (n + 1);
  }
  bm.counters["h_factor_bytes_per_world"] = h * (bm.range(3) == 1 ? 4.0 : 8.0) / worlds;
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
  label(bm, worlds);
  if (spec.floor) {
    double z = 0;
    for (const mjData* d : data) z += d->qpos[2];
    bm.counters["base_height"] = z / worlds;
  }
  bm.counters["mjdata_bytes_per_world"] = static_cast<double>(data[0]->nbuffer) + data[0]->nstack * sizeof(mjtNum);
  for (auto* d : data) mj_deleteData(d);
}

// worlds 1 .. 16384 at all threads (MuJoCo to 4096: 16384 of its mjData do not fit in 24 GiB);
// 4096 worlds at one thread too (the scaling line)
void sweep(benchmark::internal::Benchmark* b, bool novaphy) {
  const int all = omp_get_num_procs();
  for (int scene = 0; scene < (novaphy ? 5 : 4); ++scene)
    for (int precision = 0; precision < (novaphy ? 2 : 1); ++precision) {
      for (const int worlds : {1, 16, 256, 4096, 16384})
        if (novaphy || worlds <= 4096) b->Args({scene, worlds, all, precision});
      if (all > 1) b->Args({scene, 4096, 1, precision});
    }
  b->ArgNames({"scene", "worlds", "threads", "precision"})->UseRealTime();
}

BENCHMARK(BM_NovaPhyStep)->Apply([](benchmark::internal::Benchmark* b) { sweep(b, true); });
BENCHMARK(BM_MujocoStep)->Apply([](benchmark::internal::Benchmark* b) { sweep(b, false); });

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
