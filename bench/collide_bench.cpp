// Collision per shape pair: CollisionPipeline::collide over worlds that each hold one pair touching (a static
// shape and a free body's shape overlapping it by 2 mm), per world; items_per_second is worlds per second.
// With one world the narrow phase dominates; with 1024 alike worlds the broad phase runs a world per lane
// (shape_bounds on Lanes) and the narrow phase, which has no SIMD form, a pair at a time.
//   novaphy_bench_collide --benchmark_format=json
// Arguments of BM_Collide: the pair (kPairs), worlds.
#include <benchmark/benchmark.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "engine/collision/pipeline.h"
#include "engine/model/builder.h"

namespace novaphy {
namespace {

// a shape of each kind on a body (or static, body -1), its lowest point `bottom` below the body's origin
struct Kind {
  const char* name;
  Scalar bottom;
  std::function<int(ModelBuilder&, int)> add;
};

std::vector<Vec3> gem() {
  std::vector<Vec3> points;
  for (int k = 0; k < 24; ++k) {  // points on an ellipsoid, a golden-angle spiral
    const Scalar y = 1 - 2 * (k + 0.5) / 24, r = std::sqrt(1 - y * y), a = k * 2.399963;
    points.push_back(Vec3(0.1 * r * std::cos(a), 0.08 * y, 0.12 * r * std::sin(a)));
  }
  return points;
}

const std::vector<Kind>& kinds() {
  static const std::vector<Kind> table = {
      {"plane", 0, [](ModelBuilder& b, int) { return b.add_ground_plane(); }},
      {"sphere", 0.1, [](ModelBuilder& b, int body) { return b.add_shape_sphere(body, 0.1); }},
      {"box", 0.08, [](ModelBuilder& b, int body) { return b.add_shape_box(body, Vec3(0.1, 0.08, 0.12)); }},
      {"capsule", 0.05,
       [](ModelBuilder& b, int body) {
         ShapeOptions lying;
         lying.xform.q = Quat(Eigen::AngleAxis<Scalar>(M_PI / 2, Vec3::UnitZ()));
         return b.add_shape_capsule(body, 0.05, 0.1, lying);
       }},
      {"cylinder", 0.06, [](ModelBuilder& b, int body) { return b.add_shape_cylinder(body, 0.1, 0.06); }},
      {"ellipsoid", 0.07, [](ModelBuilder& b, int body) { return b.add_shape_ellipsoid(body, Vec3(0.12, 0.07, 0.1)); }},
      {"mesh", 0.08, [](ModelBuilder& b, int body) { return b.add_shape_mesh(body, b.add_mesh(gem())); }},
  };
  return table;
}

// the pairs: a plane, then each kind under each kind at least as late in the table
std::vector<std::pair<int, int>> pairs() {
  std::vector<std::pair<int, int>> list;
  for (int a = 0; a < static_cast<int>(kinds().size()); ++a)
    for (int b = std::max(a, 1); b < static_cast<int>(kinds().size()); ++b) list.push_back({a, b});
  return list;
}

// one world: kind a static (its top at y = 0), kind b on a free body resting 2 mm into it
ModelBuilder pair_world(int a, int b) {
  ModelBuilder world;
  const Kind &under = kinds()[a], &over = kinds()[b];
  if (a == 0) {
    under.add(world, -1);
  } else {
    const int base = world.add_body(RigidBody(), Transform{Vec3(0, -under.bottom, 0), Quat::Identity()});
    world.add_joint_fixed(-1, base);
    under.add(world, base);
  }
  const int top = world.add_body(RigidBody::from_sphere(1, 0.1),
                                 Transform{Vec3(0.01, over.bottom - 0.002, 0.005), Quat::Identity()});
  over.add(world, top);
  return world;
}

void BM_Collide(benchmark::State& bm) {
  const auto [a, b] = pairs()[bm.range(0)];
  const int worlds = static_cast<int>(bm.range(1));
  ModelBuilder builder;
  builder.replicate(pair_world(a, b), worlds, Vec3::Zero());
  const Model model = builder.finalize();
  CollisionPipeline pipeline(model);
  Contacts contacts = pipeline.contacts();
  const State state = model.state();
  for (auto _ : bm) pipeline.collide(state, contacts);
  if (contacts.contact_count < worlds) bm.SkipWithError("a world of the pair found no contact");
  bm.SetLabel(std::string(kinds()[a].name) + "-" + kinds()[b].name);
  bm.SetItemsProcessed(bm.iterations() * worlds);
  bm.counters["contacts_per_world"] = static_cast<double>(contacts.contact_count) / worlds;
}
BENCHMARK(BM_Collide)->Apply([](benchmark::internal::Benchmark* b) {
  for (int p = 0; p < static_cast<int>(pairs().size()); ++p)
    for (const int worlds : {1, 1024}) b->Args({p, worlds});
});

}  // namespace
}  // namespace novaphy

BENCHMARK_MAIN();
