// Whole steps of many robots: NovaPhy's SolverFeatherstone on replicated worlds beside MuJoCo 2.2.2
// stepping one mjData per world in the same OpenMP loop, same MJCF, same dt, same process.
//   novaphy_bench_step --benchmark_format=json
// Arguments: scene (0 chain15, 1 quadruped without a floor, 2 quadruped standing, 3 MuJoCo's
// humanoid.xml without contacts, 4 the standing quadruped with settings.pgs_tolerance = 0, the sweeps run to a
// fixed point or num_iterations, NovaPhy only: MuJoCo's reference is scene 2),
// worlds, threads, precision (NovaPhy: 0 float64, 1 float32; MuJoCo is double). items_per_second is
// robot-steps per second. BM_PairedStep (scene, precision) times both engines in alternation at 4096
// worlds, for the targets (below). tools/bench_report.py turns the JSON into the README's tables.
// The floor scenes collide at margin 0, the MJCF's own (MuJoCo's default geom margin): contacts where shapes
// touch, the same four a robot MuJoCo finds; at the pipeline's default 1 cm the shins' capsule ends, 5 mm
// above the floor, add four speculative contacts a robot (the README gives both speeds)
#include <benchmark/benchmark.h>
#include <omp.h>
#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "bench/bench_scenes.h"
#include "engine/import/mjcf_import.h"
#include "engine/solver/solver_featherstone.h"

namespace novaphy {
namespace {

struct SceneSpec {
  const char* path;
  bool floor;
  Scalar pgs_tolerance = SolverFeatherstoneSettings{}.pgs_tolerance;
};
const SceneSpec kScenes[] = {{NOVAPHY_SCENE_DIR "/chain15.xml", false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", true},
                             {NOVAPHY_HUMANOID_XML, false},
                             {NOVAPHY_SCENE_DIR "/quadruped.xml", true, 0}};
// the scene MuJoCo steps beside each: the tolerance changes only NovaPhy's settings
constexpr int kMujocoScene[] = {0, 1, 2, 3, 2};

constexpr Scalar kDt = 0.005;
constexpr int kSettleSteps = 50;  // onto the floor, before timing

void label(benchmark::State& bm, int worlds) {
  bm.SetItemsProcessed(bm.iterations() * worlds);
  bm.counters["scene"] = static_cast<double>(bm.range(0));
  bm.counters["worlds"] = worlds;
  bm.counters["threads"] = static_cast<double>(bm.range(2));
  bm.counters["precision"] = static_cast<double>(bm.range(3));
}

CollisionOptions collision_options(int threads) {
  CollisionOptions options;
  options.num_threads = threads;
  options.margin = 0;
  options.count_serial_time = true;
  return options;
}

SolverFeatherstoneSettings solver_settings(const SceneSpec& spec, int threads) {
  SolverFeatherstoneSettings settings;
  settings.num_threads = threads;
  settings.pgs_tolerance = spec.pgs_tolerance;
  settings.count_serial_time = true;
  return settings;
}

// NovaPhy's side of a scene: its replicated worlds, collided (the floor scenes) and stepped on `threads` threads
struct NovaPhyWorlds {
  NovaPhyWorlds(const SceneSpec& spec, int worlds, int threads, Precision precision)
      : floor(spec.floor),
        model(replicated_mjcf(spec.path, worlds, precision, spec.floor)),
        pipeline(model, collision_options(threads)),
        contacts(pipeline.contacts()),
        solver(model, solver_settings(spec, threads)),
        state(model.state()),
        control(model.control()) {
    for (int k = 0; k < kSettleSteps; ++k) step();
    reset_serial_seconds();
  }
  void step() {
    if (floor) pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, kDt);
  }
  void reset_serial_seconds() {
    solver.reset_serial_seconds();
    pipeline.reset_serial_seconds();
  }
  // the share of a step's wall time (collide's, on the floor scenes, and the solver's) outside their parallel work
  double serial_share() const {
    const SerialSeconds &s = solver.serial_seconds(), &c = pipeline.serial_seconds();
    const double wall = s.step + (floor ? c.step : 0);
    return wall > 0 ? (wall - s.parallel - (floor ? c.parallel : 0)) / wall : 0;
  }
  // the floor scenes' robots still standing: their base's mean height
  double base_height() const { return mean_base_height(model, state); }
  bool floor;
  Model model;
  CollisionPipeline pipeline;
  Contacts contacts;
  SolverFeatherstone solver;
  State state;
  Control control;
};

// MuJoCo's side: one mjData per world, stepped in an OpenMP loop
struct MujocoWorlds {
  MujocoWorlds(const SceneSpec& spec, int worlds) : m(load_mujoco_model(spec.path), mj_deleteModel), data(worlds) {
    if (!spec.floor) m->opt.disableflags |= mjDSBL_CONTACT;
    m->opt.timestep = kDt;
    for (auto& d : data) d = mj_makeData(m.get());
    for (int k = 0; k < kSettleSteps; ++k)
      for (auto* d : data) mj_step(m.get(), d);
  }
  ~MujocoWorlds() {
    for (auto* d : data) mj_deleteData(d);
  }
  MujocoWorlds(const MujocoWorlds&) = delete;
  MujocoWorlds& operator=(const MujocoWorlds&) = delete;
  void step(int threads) {
    const int worlds = static_cast<int>(data.size());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int w = 0; w < worlds; ++w) mj_step(m.get(), data[w]);
  }
  double base_height() const {
    double z = 0;
    for (const mjData* d : data) z += d->qpos[2];
    return z / static_cast<double>(data.size());
  }
  std::unique_ptr<mjModel, void (*)(mjModel*)> m;
  std::vector<mjData*> data;
};

void BM_NovaPhyStep(benchmark::State& bm) {
  const SceneSpec& spec = kScenes[bm.range(0)];
  const int worlds = static_cast<int>(bm.range(1));
  NovaPhyWorlds nova(spec, worlds, static_cast<int>(bm.range(2)),
                     bm.range(3) == 1 ? Precision::Float32 : Precision::Float64);
  for (auto _ : bm) nova.step();
  label(bm, worlds);
  if (spec.floor) bm.counters["base_height"] = nova.base_height();
  bm.counters["serial_share"] = nova.serial_share();
  // memory per world: what the solver holds, the State's arrays, and H with its factor (two packed
  // triangles in the model's precision): the least a world can be stepped in
  const Model& model = nova.model;
  const State& state = nova.state;
  bm.counters["solver_bytes_per_world"] = static_cast<double>(nova.solver.memory_bytes()) / worlds;
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
  MujocoWorlds mujoco(spec, worlds);
  const int threads = static_cast<int>(bm.range(2));
  for (auto _ : bm) mujoco.step(threads);
  label(bm, worlds);
  if (spec.floor) bm.counters["base_height"] = mujoco.base_height();
  bm.counters["mjdata_bytes_per_world"] =
      static_cast<double>(mujoco.data[0]->nbuffer) + mujoco.data[0]->nstack * sizeof(mjtNum);
}

// seconds of all CPUs' time taken by the host for other guests so far (Linux's steal time; 0 where the
// kernel does not say)
double steal_seconds() {
  std::ifstream stat("/proc/stat");
  std::string cpu;
  double field[8] = {};
  stat >> cpu;
  for (double& x : field) stat >> x;
  return stat ? field[7] / static_cast<double>(sysconf(_SC_CLK_TCK)) : 0;
}

// the CPUs the one-thread runs are pinned to in turn: the first of each OpenMP place (OMP_PLACES), or else
// each CPU this thread may run on
std::vector<int> one_thread_cpus() {
  std::vector<int> cpus;
  for (int p = 0; p < omp_get_num_places(); ++p) {
    std::vector<int> ids(omp_get_place_num_procs(p));
    if (ids.empty()) continue;
    omp_get_place_proc_ids(p, ids.data());
    cpus.push_back(ids[0]);
  }
  cpu_set_t mask;
  if (cpus.empty() && sched_getaffinity(0, sizeof(mask), &mask) == 0)
    for (int c = 0; c < CPU_SETSIZE; ++c)
      if (CPU_ISSET(c, &mask)) cpus.push_back(c);
  return cpus;
}

// f() with the calling thread on `cpu` alone, then its CPU mask as it was; false (f not run) where the
// system refuses the CPU
template <typename F>
bool on_cpu(int cpu, F&& f) {
  cpu_set_t before, only;
  CPU_ZERO(&only);
  CPU_SET(cpu, &only);
  if (pthread_getaffinity_np(pthread_self(), sizeof(before), &before) != 0 ||
      pthread_setaffinity_np(pthread_self(), sizeof(only), &only) != 0)
    return false;
  f();
  pthread_setaffinity_np(pthread_self(), sizeof(before), &before);
  return true;
}

double median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  const size_t n = x.size();
  return n % 2 ? x[n / 2] : (x[n / 2 - 1] + x[n / 2]) / 2;
}

// the wall time of `steps` calls of run(), after as many not timed
template <typename F>
double seconds(F&& run, int steps) {
  for (int k = 0; k < steps; ++k) run();
  const std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  for (int k = 0; k < steps; ++k) run();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The targets' figures side by side: at 4096 worlds, each iteration (a round) times runs of steps in
// turn, their order rotating from round to round: NovaPhy on all threads, NovaPhy on one thread pinned to
// each core in turn, MuJoCo on all, MuJoCo on one pinned to each core (NovaPhy's runs on two copies of the
// worlds, each with its own pipeline's thread count; both copies take the same steps). A slow spell of the
// machine then falls on all of them within a second or two, and each round gives its own ratios; the
// counters are the medians over rounds of each engine's robot-steps/s and of the ratios NovaPhy / MuJoCo on
// all threads and all threads / one thread on the first core (the speed-ups). The cores' own speeds: a
// guest's vCPUs can step one thread's work at unequal speeds (the host's other guests on their cores), and
// no team beats its cores' one-thread speeds added; core_spread is the slowest core's one-thread rate over
// the fastest's, core_use the team's rate over the one-thread rates on its cores added (1: all threads
// together lose nothing to each other), both per round, for either engine.
// A run is at least 20 ms: MuJoCo's of k_mujoco steps, NovaPhy's of as many steps as take about as long,
// each after as many steps not timed as it times: as long as the run, for both engines alike (the engine's
// data back in cache after the other's run, and a core the other left idle awake again: after one step
// not timed, ~1.3 ms of NovaPhy's, its first timed steps after MuJoCo's run on one thread took up to ~10x
// their time; the idle OpenMP threads stop spinning meanwhile, so a pinned run has its core alone: not with
// OMP_WAIT_POLICY=active)
void BM_PairedStep(benchmark::State& bm) {
  using Clock = std::chrono::steady_clock;
  const SceneSpec& spec = kScenes[bm.range(0)];
  constexpr int kWorlds = 4096;
  const int all = omp_get_num_procs();
  const std::vector<int> cpus = one_thread_cpus();
  const int cores = static_cast<int>(cpus.size());
  if (cores == 0) return bm.SkipWithError("no CPU to pin the one-thread runs to");
  const Precision precision = bm.range(1) == 1 ? Precision::Float32 : Precision::Float64;
  NovaPhyWorlds nova_all(spec, kWorlds, all, precision), nova_one(spec, kWorlds, 1, precision);
  MujocoWorlds mujoco(kScenes[kMujocoScene[bm.range(0)]], kWorlds);
  auto both_novaphy = [&] {  // (the two copies stay at the same step)
    nova_all.step();
    nova_one.step();
  };
  const double mujoco_step = seconds([&] { mujoco.step(all); }, 1);
  const double nova_step = seconds(both_novaphy, 1) / 2;
  const int k_mujoco = std::max(1, static_cast<int>(std::ceil(0.02 / mujoco_step)));
  const int k_nova = std::max(1, static_cast<int>(std::lround(k_mujoco * mujoco_step / nova_step)));
  // a round's runs: 0 NovaPhy on all threads, 1 + c NovaPhy on one thread on core c, 1 + cores MuJoCo on
  // all, 2 + cores + c MuJoCo on one on core c
  const int runs = 2 + 2 * cores;
  std::vector<std::vector<double>> rate(runs);  // robot-steps/s
  const double steal_before = steal_seconds();
  const Clock::time_point start = Clock::now();
  std::vector<double> ratio, speedup[2], core_use[2], core_spread[2];
  int round = 0;
  for (auto _ : bm) {
    std::vector<double> r(runs);
    for (int turn = 0; turn < runs; ++turn) {
      const int run = (turn + round) % runs, engine = run / (1 + cores), core = run % (1 + cores) - 1;
      const int steps = engine == 0 ? k_nova : k_mujoco;
      auto step = [&] {
        if (engine == 1) return mujoco.step(core < 0 ? all : 1);
        return core < 0 ? nova_all.step() : nova_one.step();
      };
      double t = 0;
      if (core < 0)
        t = seconds(step, steps);
      else if (!on_cpu(cpus[core], [&] { t = seconds(step, steps); }))
        return bm.SkipWithError(("cannot pin a thread to CPU " + std::to_string(cpus[core])).c_str());
      r[run] = static_cast<double>(kWorlds) * steps / t;
      rate[run].push_back(r[run]);
    }
    ratio.push_back(r[0] / r[1 + cores]);
    for (int engine = 0; engine < 2; ++engine) {
      const double team = r[engine * (1 + cores)], *one = &r[engine * (1 + cores) + 1];
      speedup[engine].push_back(team / one[0]);
      core_use[engine].push_back(team / std::accumulate(one, one + cores, 0.0));
      core_spread[engine].push_back(*std::min_element(one, one + cores) / *std::max_element(one, one + cores));
    }
    ++round;
  }
  // the share of the cores' time the machine's host gave to others while the rounds ran
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  bm.counters["steal"] = (steal_seconds() - steal_before) / (wall * all);
  bm.counters["scene"] = static_cast<double>(bm.range(0));
  bm.counters["precision"] = static_cast<double>(bm.range(1));
  bm.counters["worlds"] = kWorlds;
  bm.counters["threads"] = all;
  bm.counters["cores"] = cores;
  bm.counters["novaphy_all"] = median(rate[0]);
  bm.counters["novaphy_one"] = median(rate[1]);
  bm.counters["mujoco_all"] = median(rate[1 + cores]);
  bm.counters["mujoco_one"] = median(rate[2 + cores]);
  bm.counters["ratio"] = median(ratio);
  const char* const name[] = {"novaphy", "mujoco"};
  for (int engine = 0; engine < 2; ++engine) {
    bm.counters[std::string(name[engine]) + "_speedup"] = median(speedup[engine]);
    bm.counters[std::string(name[engine]) + "_core_use"] = median(core_use[engine]);
    bm.counters[std::string(name[engine]) + "_core_spread"] = median(core_spread[engine]);
  }
  bm.counters["novaphy_steps"] = k_nova;
  bm.counters["mujoco_steps"] = k_mujoco;
}

// The thread sweep: at `worlds` worlds, each engine on 1, 2, 4, ... threads and on all (NovaPhy on a copy of
// the worlds per thread count, all taking the same steps), in alternating rounds as BM_PairedStep's (each
// round runs every line once, the order rotating; runs of at least 20 ms after as many steps not timed).
// Counters per thread count t: each engine's robot-steps/s (median over rounds), its speed-up over one
// thread and parallel efficiency (the speed-up over t), the ratio NovaPhy / MuJoCo, and NovaPhy's serial
// share (collide's and the solver's serial_seconds: the step's wall time outside their parallel work over the whole,
// over all rounds). MuJoCo to 4096 worlds (its mjData of 16384 do not fit in 24 GiB); tools/scaling.sh runs it.
std::vector<int> thread_counts() {
  const int all = omp_get_num_procs();
  std::vector<int> counts;
  for (int t = 1; t < all; t *= 2) counts.push_back(t);
  counts.push_back(all);
  return counts;
}

void BM_ThreadSweep(benchmark::State& bm) {
  const SceneSpec& spec = kScenes[bm.range(0)];
  const Precision precision = bm.range(1) == 1 ? Precision::Float32 : Precision::Float64;
  const int worlds = static_cast<int>(bm.range(2));
  const bool with_mujoco = worlds <= 4096;
  const std::vector<int> threads = thread_counts();
  const int n = static_cast<int>(threads.size());
  std::vector<std::unique_ptr<NovaPhyWorlds>> nova;
  for (const int t : threads) nova.push_back(std::make_unique<NovaPhyWorlds>(spec, worlds, t, precision));
  std::unique_ptr<MujocoWorlds> mujoco;
  if (with_mujoco) mujoco = std::make_unique<MujocoWorlds>(kScenes[kMujocoScene[bm.range(0)]], worlds);
  // lines 0 .. n-1 NovaPhy on threads[i], n .. 2n-1 MuJoCo; each line's steps make a run of about 20 ms
  const int lines = with_mujoco ? 2 * n : n;
  auto step = [&](int line) {
    if (line < n) return nova[line]->step();
    mujoco->step(threads[line - n]);
  };
  std::vector<int> steps(lines);
  for (int line = 0; line < lines; ++line) {
    const double one = seconds([&] { step(line); }, 1);
    steps[line] = std::max(1, static_cast<int>(std::ceil(0.02 / one)));
  }
  for (auto& copy : nova) copy->reset_serial_seconds();
  std::vector<std::vector<double>> rate(lines);
  int round = 0;
  for (auto _ : bm) {
    for (int turn = 0; turn < lines; ++turn) {
      const int line = (turn + round) % lines;
      rate[line].push_back(static_cast<double>(worlds) * steps[line] / seconds([&] { step(line); }, steps[line]));
    }
    ++round;
  }
  bm.counters["scene"] = static_cast<double>(bm.range(0));
  bm.counters["precision"] = static_cast<double>(bm.range(1));
  bm.counters["worlds"] = worlds;
  for (int i = 0; i < n; ++i) {
    const std::string t = "_t" + std::to_string(threads[i]);
    const double nova_rate = median(rate[i]), nova_one = median(rate[0]);
    bm.counters["novaphy" + t] = nova_rate;
    bm.counters["novaphy_speedup" + t] = nova_rate / nova_one;
    bm.counters["novaphy_efficiency" + t] = nova_rate / nova_one / threads[i];
    bm.counters["serial_share" + t] = nova[i]->serial_share();
    if (!with_mujoco) continue;
    const double mujoco_rate = median(rate[n + i]), mujoco_one = median(rate[n]);
    bm.counters["mujoco" + t] = mujoco_rate;
    bm.counters["mujoco_speedup" + t] = mujoco_rate / mujoco_one;
    bm.counters["mujoco_efficiency" + t] = mujoco_rate / mujoco_one / threads[i];
    bm.counters["ratio" + t] = nova_rate / mujoco_rate;
  }
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
// its rounds are its repetitions: one run of 16, whatever --benchmark_repetitions says
BENCHMARK(BM_PairedStep)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1}})
    ->ArgNames({"scene", "precision"})
    ->Iterations(16)
    ->Repetitions(1)
    ->UseRealTime();
// scenes 1 (quadruped, no floor), 2 (standing) and 3 (humanoid.xml); its rounds are its repetitions
BENCHMARK(BM_ThreadSweep)
    ->ArgsProduct({{1, 2, 3}, {0, 1}, {256, 512, 1024, 4096, 16384}})
    ->ArgNames({"scene", "precision", "worlds"})
    ->Iterations(9)
    ->Repetitions(1)
    ->UseRealTime();

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
