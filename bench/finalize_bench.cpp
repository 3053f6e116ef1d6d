// Model set-up cost on long chains: ModelBuilder::finalize on a revolute chain of n links (a capsule on each) in
// one world and replicated into many, and what a user calls next on the model (model.state(), the solver's and
// the collision pipeline's constructors); and the kernel behind body_invweight0 beside its previous, dense version.
//   novaphy_bench_finalize --benchmark_filter=BM_Finalize
// Arguments: links, worlds (BM_OsimInverse: links, path 0 the O(n) recursion, 1 the dense reference). items_per_second
// is links (over all worlds) per second.
#include <benchmark/benchmark.h>

#include "engine/collision/pipeline.h"
#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"
#include "kernels/fk.h"
#include "kernels/osim.h"

namespace novaphy {
namespace {

// a revolute chain of n links along +X, each a 0.1 kg box's inertia with a capsule shape
ModelBuilder chain(int n) {
  ModelBuilder builder;
  int parent = -1;
  for (int i = 0; i < n; ++i) {
    const int link = builder.add_body(RigidBody::from_box(0.1, Vec3(0.05, 0.01, 0.01)));
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.dof.armature = 0.001;
    options.parent_xform.p = parent < 0 ? Vec3::Zero() : Vec3(0.05, 0, 0);
    options.child_xform.p = Vec3(-0.05, 0, 0);
    builder.add_joint_revolute(parent, link, options);
    ShapeOptions shape;
    shape.xform.q = Quat(Eigen::AngleAxis<Scalar>(M_PI / 2, Vec3::UnitZ()));
    builder.add_shape_capsule(link, 0.01, 0.04, shape);
    parent = link;
  }
  return builder;
}

// the chain of range(0) links replicated into range(1) worlds, 1 m apart
ModelBuilder scene(const benchmark::State& bm) {
  const ModelBuilder robot = chain(static_cast<int>(bm.range(0)));
  ModelBuilder builder;
  builder.replicate(robot, static_cast<int>(bm.range(1)), Vec3(0, 0, 1));
  return builder;
}

void count(benchmark::State& bm) {
  bm.SetItemsProcessed(bm.iterations() * bm.range(0) * bm.range(1));
  bm.counters["links"] = static_cast<double>(bm.range(0));
  bm.counters["worlds"] = static_cast<double>(bm.range(1));
}

void BM_Finalize(benchmark::State& bm) {
  const ModelBuilder builder = scene(bm);
  for (auto _ : bm) benchmark::DoNotOptimize(builder.finalize());
  count(bm);
}

void BM_Replicate(benchmark::State& bm) {
  const ModelBuilder robot = chain(static_cast<int>(bm.range(0)));
  for (auto _ : bm) {
    ModelBuilder builder;
    builder.replicate(robot, static_cast<int>(bm.range(1)), Vec3(0, 0, 1));
    benchmark::DoNotOptimize(builder);
  }
  count(bm);
}

void BM_ModelState(benchmark::State& bm) {
  const Model model = scene(bm).finalize();
  for (auto _ : bm) benchmark::DoNotOptimize(model.state());
  count(bm);
}

void BM_SolverConstruct(benchmark::State& bm) {
  const Model model = scene(bm).finalize();
  for (auto _ : bm) {
    SolverFeatherstone solver(model);
    benchmark::DoNotOptimize(solver);
  }
  count(bm);
}

void BM_PipelineConstruct(benchmark::State& bm) {
  const Model model = scene(bm).finalize();
  for (auto _ : bm) {
    CollisionPipeline pipeline(model);
    benchmark::DoNotOptimize(pipeline);
  }
  count(bm);
}

// every link's inverse operational-space inertia on one chain at joint_q0: osim_inverse (O(n)) and its reference
// twin osim_inverse_ref (dense H, Cholesky and six solves a link: O(n^3)), which finalize used before
void BM_OsimInverse(benchmark::State& bm) {
  const Model model = chain(static_cast<int>(bm.range(0))).finalize();
  const ArticulationView art = model.articulation(0);
  ArticulationScratch s;
  s.resize(art);
  forward_kinematics(art, model.joint_q0.data(), s);
  std::vector<Mat6> Omega;
  for (auto _ : bm)
    benchmark::DoNotOptimize(bm.range(1) == 0 ? osim_inverse(art, s, Omega) : osim_inverse_ref(art, s, Omega));
  bm.SetItemsProcessed(bm.iterations() * bm.range(0));
  bm.counters["links"] = static_cast<double>(bm.range(0));
  bm.SetLabel(bm.range(1) == 0 ? "recursion" : "dense");
}

// one world: 100 to 10,000 links; 1000 links in 1 to 1024 worlds
void sizes(benchmark::internal::Benchmark* b) {
  for (const int n : {100, 300, 1000, 3000, 10000}) b->Args({n, 1});
  for (const int worlds : {4, 16, 64, 256, 1024}) b->Args({100, worlds});
  for (const int worlds : {4, 16, 64, 256, 1024}) b->Args({1000, worlds});
  b->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_Finalize)->Apply(sizes);
BENCHMARK(BM_Replicate)->Apply(sizes);
BENCHMARK(BM_ModelState)->Apply(sizes);
BENCHMARK(BM_SolverConstruct)->Apply(sizes);
BENCHMARK(BM_PipelineConstruct)->Apply(sizes);
BENCHMARK(BM_OsimInverse)
    ->ArgsProduct({{10, 30, 100, 300, 1000}, {0, 1}})
    ->Args({3000, 0})
    ->Args({10000, 0})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
