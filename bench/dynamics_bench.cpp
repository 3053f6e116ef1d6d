// Forward dynamics of one robot, NovaPhy's reference kernels beside MuJoCo 2.2.2 on the same MJCF
// (contacts and limits off): the single-world baseline the batched kernels are measured against.
// BM_NovaPhyForwardDynamics: the same through ForwardDynamics (engine/eval/eval.h: the step's batched kernels, the
// robot alone in a block made once; argument 2: precision, 0 float64, 1 float32), the input checks and the
// control forces included as mj_forward includes them: what one robot costs on the step's own path.
//   novaphy_bench_dynamics --benchmark_format=json
#include <benchmark/benchmark.h>

#include <memory>

#include "engine/eval/eval.h"
#include "engine/import/mjcf_import.h"
#include "kernels/aba.h"
#include "kernels/cholesky.h"
#include "kernels/crba.h"
#include "kernels/fk.h"
#include "kernels/rnea.h"

namespace novaphy {
namespace {

const char* const kScenes[] = {NOVAPHY_SCENE_DIR "/chain15.xml", NOVAPHY_SCENE_DIR "/quadruped.xml",
                               "/usr/share/mujoco/model/humanoid/humanoid.xml"};

// one scene loaded once into both engines, at a fixed state with joint forces
struct Scene {
  explicit Scene(const char* path)
      : m(load_mujoco_model(path), mj_deleteModel), d(mj_makeData(m.get()), mj_deleteData) {
    m->opt.disableflags |= mjDSBL_CONSTRAINT;
    for (int k = 0; k < m->nv; ++k) d->qvel[k] = 0.1 * (k % 5) - 0.2, d->qfrc_applied[k] = 0.5 * (k % 3) - 0.5;
    ModelBuilder builder;
    import = import_mujoco_model(builder, m.get());
    model = builder.finalize();
    state = model.state();
    import.to_joint_q(d->qpos, state.joint_q.data());
    import.to_joint_qd(d->qpos, d->qvel, state.joint_qd.data());
    tau.setConstant(model.joint_dof_count, 0.3);
    qdd.setZero(model.joint_dof_count);
    zero.setZero(model.joint_dof_count);
    art = model.articulation(0);
    scratch.resize(art);
  }
  std::unique_ptr<mjModel, void (*)(mjModel*)> m;
  std::unique_ptr<mjData, void (*)(mjData*)> d;
  MujocoImport import;
  Model model;
  State state;
  VecX tau, qdd, zero;
  ArticulationView art;
  ArticulationScratch scratch;
};

Scene& scene(int index) {
  static std::unique_ptr<Scene> scenes[std::size(kScenes)];
  if (!scenes[index]) scenes[index] = std::make_unique<Scene>(kScenes[index]);
  return *scenes[index];
}

void label(benchmark::State& bm, const Scene& s) {
  bm.SetItemsProcessed(bm.iterations());
  bm.SetLabel(std::string(s.m->names) + " nv=" + std::to_string(s.model.joint_dof_count));
}

void BM_NovaPhyCrbaCholesky(benchmark::State& bm) {
  Scene& s = scene(bm.range(0));
  for (auto _ : bm) {
    forward_kinematics(s.art, s.state.joint_q.data(), s.scratch);
    forward_velocity(s.art, s.state.joint_qd.data(), s.scratch);
    rnea(s.art, s.zero.data(), s.model.gravity, nullptr, s.scratch, s.qdd.data());
    s.qdd = s.tau - s.qdd;
    crba(s.art, s.scratch);
    cholesky_factor(s.scratch.H);
    cholesky_solve(s.scratch.H, s.qdd.data());
    benchmark::DoNotOptimize(s.qdd.data());
  }
  label(bm, s);
}

void BM_NovaPhyAba(benchmark::State& bm) {
  Scene& s = scene(bm.range(0));
  for (auto _ : bm) {
    forward_kinematics(s.art, s.state.joint_q.data(), s.scratch);
    forward_velocity(s.art, s.state.joint_qd.data(), s.scratch);
    aba(s.art, s.tau.data(), s.model.gravity, nullptr, s.scratch, s.qdd.data());
    benchmark::DoNotOptimize(s.qdd.data());
  }
  label(bm, s);
}

void BM_MujocoForward(benchmark::State& bm) {
  Scene& s = scene(bm.range(0));
  for (auto _ : bm) {
    mj_forward(s.m.get(), s.d.get());
    benchmark::DoNotOptimize(s.d->qacc);
  }
  label(bm, s);
}

void BM_NovaPhyForwardDynamics(benchmark::State& bm) {
  Scene& s = scene(bm.range(0));
  ModelBuilder builder;
  import_mujoco_model(builder, s.m.get());
  builder.set_precision(bm.range(1) == 1 ? Precision::Float32 : Precision::Float64);
  const Model model = builder.finalize();
  Control control = model.control();
  for (int k = 0; k < model.joint_dof_count; ++k) control.joint_f[k] = s.tau[k];
  ForwardDynamics dynamics(model);
  for (auto _ : bm) {
    dynamics.evaluate(s.state, control, s.qdd.data());
    benchmark::DoNotOptimize(s.qdd.data());
  }
  label(bm, s);
}

BENCHMARK(BM_NovaPhyCrbaCholesky)->DenseRange(0, std::size(kScenes) - 1);
BENCHMARK(BM_NovaPhyAba)->DenseRange(0, std::size(kScenes) - 1);
BENCHMARK(BM_MujocoForward)->DenseRange(0, std::size(kScenes) - 1);
BENCHMARK(BM_NovaPhyForwardDynamics)->ArgsProduct({{0, 1, 2}, {0, 1}});

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
