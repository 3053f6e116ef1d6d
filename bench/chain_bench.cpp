// A revolute chain of n links (no XML) stepped by SolverFeatherstone with the ABA path (O(n)) and
// with CRBA + Cholesky (O(n^2) + O(n^3)): the cost per step across 8 to 1000 links.
//   novaphy_bench_chain --benchmark_format=json
// Arguments: links, path (0 ABA, 1 CRBA + Cholesky). items_per_second is link-steps per second.
#include <benchmark/benchmark.h>

#include "engine/model/builder.h"
#include "engine/solver/solver_featherstone.h"

namespace novaphy {
namespace {

void BM_ChainStep(benchmark::State& bm) {
  const int n = static_cast<int>(bm.range(0));
  ModelBuilder builder;
  int parent = -1;
  for (int i = 0; i < n; ++i) {
    const int link = builder.add_body(RigidBody::from_box(0.1, Vec3(0.05, 0.01, 0.01)));
    JointOptions options;
    options.dof.axis = Vec3::UnitZ();
    options.parent_xform.p = parent < 0 ? Vec3::Zero() : Vec3(0.05, 0, 0);
    options.child_xform.p = Vec3(-0.05, 0, 0);
    builder.add_joint_revolute(parent, link, options);
    parent = link;
  }
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  SolverFeatherstoneSettings settings;
  settings.aba_min_dofs = bm.range(1) == 0 ? 0 : n + 1;
  settings.num_threads = 1;
  SolverFeatherstone solver(model, settings);
  State state = model.state();
  const Control control = model.control();
  for (auto _ : bm) {
    pipeline.collide(state, contacts);
    solver.step(state, state, control, contacts, 1e-4);
  }
  bm.SetItemsProcessed(bm.iterations() * n);
  bm.counters["links"] = n;
  bm.SetLabel(bm.range(1) == 0 ? "ABA" : "CRBA+Cholesky");
}

BENCHMARK(BM_ChainStep)->ArgsProduct({{8, 10, 16, 32, 64, 100, 128, 1000}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
