#include "engine/collision.h"

#include <omp.h>

#include <algorithm>
#include <numeric>

#include "engine/error.h"
#include "kernels/collide.h"

namespace novaphy {

std::uint64_t Contacts::key(int shape_a, int shape_b, int feature) {
  return (static_cast<std::uint64_t>(shape_a) << 40) | (static_cast<std::uint64_t>(shape_b) << 16) |
         static_cast<std::uint64_t>(feature & 0xffff);
}

const Scalar* Contacts::previous(int c) const {
  const std::uint64_t k = key(contact_shape_a[c], contact_shape_b[c], contact_feature[c]);
  const auto end = previous_key.begin() + previous_count;
  const auto it = std::lower_bound(previous_key.begin(), end, k);
  if (it == end || *it != k) return nullptr;
  return &previous_impulse[3 * (it - previous_key.begin())];
}

CollisionPipeline::CollisionPipeline(const Model& model, const CollisionOptions& options)
    : model_(model), options_(options) {
  if (options.contact_capacity < 0) fail("contact_capacity must be >= 0, got ", options.contact_capacity);
  if (!(options.margin >= 0) || !std::isfinite(options.margin))
    fail("margin must be finite and >= 0, got ", options.margin);
  if (options.num_threads < 0) fail("num_threads must be >= 0 (0: OpenMP's default), got ", options.num_threads);
  if (options_.contact_capacity == 0) options_.contact_capacity = std::max(64, 8 * model.shape_count);
  body_parent_.assign(model.body_count, -1);
  body_articulation_.assign(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) {
    // the parent through massless links (a MuJoCo body with several joints is a chain of them)
    int parent = model.joint_parent[j];
    while (parent >= 0 && model.body_mass[parent] == 0) parent = body_parent_[parent];
    body_parent_[model.joint_child[j]] = parent;
    body_articulation_[model.joint_child[j]] = model.joint_articulation[j];
  }
  world_others_.resize(model.world_count);
  for (int s = 0; s < model.shape_count; ++s) {
    // a shape with an empty group or mask never collides: the broad phase never sees it
    if (model.shape_collision_group[s] == 0 || model.shape_collision_mask[s] == 0) continue;
    if (model.shape_type[s] == static_cast<int>(ShapeType::Plane)) {
      planes_.push_back(s);
      continue;
    }
    others_.push_back(s);
    const int w = model.shape_world[s];
    (w < 0 ? shared_others_ : world_others_[w]).push_back(s);
  }
  lower_.resize(3 * model.shape_count);
  upper_.resize(3 * model.shape_count);
}

Contacts CollisionPipeline::contacts() const {
  Contacts c;
  static_cast<ModelCounts&>(c) = model_;
  c.contact_capacity = options_.contact_capacity;
#define NOVAPHY_ALLOCATE_CONTACT(T, name, count, width) c.name.assign(static_cast<size_t>(c.count) * (width), T{});
  NOVAPHY_CONTACT_FIELDS(NOVAPHY_ALLOCATE_CONTACT)
#undef NOVAPHY_ALLOCATE_CONTACT
  c.previous_key.resize(c.contact_capacity);
  c.previous_impulse.resize(3 * c.contact_capacity);
  return c;
}

bool CollisionPipeline::may_collide(int a, int b) const {
  const int ba = model_.shape_body[a], bb = model_.shape_body[b];
  if (ba == bb) return false;
  const int wa = model_.shape_world[a], wb = model_.shape_world[b];
  if (wa >= 0 && wb >= 0 && wa != wb) return false;
  if ((model_.shape_collision_group[a] & model_.shape_collision_mask[b]) == 0 ||
      (model_.shape_collision_group[b] & model_.shape_collision_mask[a]) == 0)
    return false;
  if (ba < 0 || bb < 0) return true;
  if (body_parent_[ba] == bb || body_parent_[bb] == ba) return false;
  return options_.self_collision || body_articulation_[ba] != body_articulation_[bb];
}

namespace {

Transform shape_pose(const Model& model, const State& state, int s) {
  const Transform local = Transform::from_array(&model.shape_transform[7 * s]);
  const int b = model.shape_body[s];
  return b < 0 ? local : Transform::from_array(&state.body_q[7 * b]) * local;
}

// world AABB of a sphere, box or capsule
void shape_bounds(const Model& model, const Transform& X, int s, Scalar margin, Scalar* lower, Scalar* upper) {
  const Vec3 scale = Eigen::Map<const Vec3>(&model.shape_scale[3 * s]);
  Vec3 extent = Vec3::Zero();
  switch (static_cast<ShapeType>(model.shape_type[s])) {
    case ShapeType::Sphere: extent = Vec3::Constant(scale.x()); break;
    case ShapeType::Box: extent = X.rotation().cwiseAbs() * scale; break;
    case ShapeType::Capsule: extent = (X.q * Vec3(0, scale.y(), 0)).cwiseAbs() + Vec3::Constant(scale.x()); break;
    case ShapeType::Plane: break;
  }
  Eigen::Map<Vec3>{lower} = X.p - extent - Vec3::Constant(margin);
  Eigen::Map<Vec3>{upper} = X.p + extent + Vec3::Constant(margin);
}

}  // namespace

void CollisionPipeline::collide(const State& state, Contacts& contacts) {
  model_.check(state);
  if (!same_layout(contacts, model_) || contacts.contact_capacity != options_.contact_capacity)
    fail("contacts buffer was not made by this pipeline (shape_count ", contacts.shape_count, ", capacity ",
         contacts.contact_capacity, "; expected ", model_.shape_count, ", ", options_.contact_capacity, ")");

  // keep this step's contacts, sorted by key, for warm starting
  sort_index_.resize(contacts.contact_count);
  std::iota(sort_index_.begin(), sort_index_.end(), 0);
  auto key_of = [&](int c) {
    return Contacts::key(contacts.contact_shape_a[c], contacts.contact_shape_b[c], contacts.contact_feature[c]);
  };
  std::sort(sort_index_.begin(), sort_index_.end(), [&](int x, int y) { return key_of(x) < key_of(y); });
  for (int k = 0; k < contacts.contact_count; ++k) {
    contacts.previous_key[k] = key_of(sort_index_[k]);
    for (int i = 0; i < 3; ++i) contacts.previous_impulse[3 * k + i] = contacts.contact_impulse[3 * sort_index_[k] + i];
  }
  contacts.previous_count = contacts.contact_count;
  contacts.contact_count = 0;
  contacts.contact_dropped = 0;

  // broad phase per world: sweep and prune along x within each world, then the shapes every world
  // shares against all, then each plane against the shapes of its world (all worlds for a shared one);
  // worlds and planes spread over threads
  auto bounds = [&](int s) {
    shape_bounds(model_, shape_pose(model_, state, s), s, options_.margin, &lower_[3 * s], &upper_[3 * s]);
  };
  const int shapes = static_cast<int>(others_.size()), threads = team(shapes, kShapesPerThread);
  if (threads == 1) {  // (a parallel region of one thread still costs a microsecond)
    for (const int s : others_) bounds(s);
  } else {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int k = 0; k < shapes; ++k) bounds(others_[k]);
  }
  auto overlap = [&](int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (lower_[3 * b + k] > upper_[3 * a + k] || lower_[3 * a + k] > upper_[3 * b + k]) return false;
    return true;
  };
  auto test_pair = [&](int a, int b, std::vector<Found>& out) {
    if (overlap(a, b) && may_collide(a, b)) narrow_phase(std::min(a, b), std::max(a, b), state, out);
  };
  find_contacts(model_.world_count, contacts, [&](int w, std::vector<Found>& out) {
    std::vector<int>& order = world_others_[w];
    std::sort(order.begin(), order.end(),
              [&](int x, int y) { return lower_[3 * x] < lower_[3 * y] || (lower_[3 * x] == lower_[3 * y] && x < y); });
    for (size_t i = 0; i < order.size(); ++i)
      for (size_t j = i + 1; j < order.size() && lower_[3 * order[j]] <= upper_[3 * order[i]]; ++j)
        test_pair(order[i], order[j], out);
  });
  find_contacts(static_cast<int>(shared_others_.size()), contacts, [&](int i, std::vector<Found>& out) {
    for (const int b : others_)
      if (b != shared_others_[i] && (model_.shape_world[b] >= 0 || b > shared_others_[i]))
        test_pair(shared_others_[i], b, out);
  });
  find_contacts(static_cast<int>(planes_.size()), contacts, [&](int i, std::vector<Found>& out) {
    const int p = planes_[i];
    const Transform X = shape_pose(model_, state, p);
    const Vec3 n = X.q * Vec3::UnitY();
    auto against = [&](const std::vector<int>& shapes) {
      for (const int s : shapes) {
        const Vec3 lo = Eigen::Map<const Vec3>(&lower_[3 * s]), hi = Eigen::Map<const Vec3>(&upper_[3 * s]);
        const Scalar distance = n.dot(0.5 * (lo + hi) - X.p) - 0.5 * (hi - lo).cwiseAbs().dot(n.cwiseAbs());
        if (distance <= 0 && may_collide(p, s)) narrow_phase(p, s, state, out);
      }
    };
    const int w = model_.shape_world[p];
    if (w < 0) {
      against(others_);
    } else {
      against(world_others_[w]);
      against(shared_others_);
    }
  });
}

int CollisionPipeline::team(int count, int grain) const {
  // no thread wakes for less than `grain` items: a small scene stays on one
  const int threads = options_.num_threads > 0 ? options_.num_threads : omp_get_max_threads();
  return std::max(1, std::min(threads, count / grain));
}

template <typename F>
void CollisionPipeline::find_contacts(int count, Contacts& contacts, F&& f) {
  // a static schedule hands thread t the t-th run of consecutive i: the threads' lists in thread
  // order are the contacts in the order of i, and each thread writes its own after the others' before
  if (count <= 0) return;
  const int threads = team(count, kWorldsPerThread);
  if (static_cast<int>(found_.size()) < threads) found_.resize(threads);
  for (int t = 0; t < threads; ++t) found_[t].clear();
  const int first = contacts.contact_count;
  // thread t's contacts into the buffer after those of the threads before it
  auto write = [&](int t) {
    std::size_t c = first;
    for (int u = 0; u < t; ++u) c += found_[u].size();
    for (const Found& found : found_[t]) {
      if (c >= static_cast<std::size_t>(contacts.contact_capacity)) break;
      contacts.contact_shape_a[c] = found.a;
      contacts.contact_shape_b[c] = found.b;
      contacts.contact_body_a[c] = model_.shape_body[found.a];
      contacts.contact_body_b[c] = model_.shape_body[found.b];
      Eigen::Map<Vec3>(&contacts.contact_point[3 * c]) = found.point.point;
      Eigen::Map<Vec3>(&contacts.contact_normal[3 * c]) = found.point.normal;
      contacts.contact_depth[c] = found.point.depth;
      contacts.contact_feature[c] = found.point.feature;
      Eigen::Map<Vec3>(&contacts.contact_impulse[3 * c]).setZero();
      ++c;
    }
  };
  if (threads == 1) {
    for (int i = 0; i < count; ++i) f(i, found_[0]);
    write(0);
  } else {
#pragma omp parallel num_threads(threads)
    {
      const int t = omp_get_thread_num();
#pragma omp for schedule(static)
      for (int i = 0; i < count; ++i) f(i, found_[t]);
      write(t);
    }
  }
  std::size_t total = 0;
  for (int t = 0; t < threads; ++t) total += found_[t].size();
  const int kept = static_cast<int>(std::min<std::size_t>(total, contacts.contact_capacity - first));
  contacts.contact_count += kept;
  contacts.contact_dropped += static_cast<int>(total) - kept;
}

void CollisionPipeline::narrow_phase(int a, int b, const State& state, std::vector<Found>& out) const {
  if (model_.shape_type[a] > model_.shape_type[b]) std::swap(a, b);
  const auto ta = static_cast<ShapeType>(model_.shape_type[a]), tb = static_cast<ShapeType>(model_.shape_type[b]);
  const Transform Xa = shape_pose(model_, state, a), Xb = shape_pose(model_, state, b);
  const Vec3 sa = Eigen::Map<const Vec3>(&model_.shape_scale[3 * a]);
  const Vec3 sb = Eigen::Map<const Vec3>(&model_.shape_scale[3 * b]);
  const Scalar m = options_.margin;
  ContactPoint points[kMaxPairContacts];
  int count = 0;
  switch (ta) {
    case ShapeType::Plane:
      if (tb == ShapeType::Sphere) count = collide_plane_sphere(Xa, Xb.p, sb.x(), m, points);
      if (tb == ShapeType::Box) count = collide_plane_box(Xa, Xb, sb, m, points);
      if (tb == ShapeType::Capsule) count = collide_plane_capsule(Xa, Xb, sb.x(), sb.y(), m, points);
      break;
    case ShapeType::Sphere:
      if (tb == ShapeType::Sphere) count = collide_sphere_sphere(Xa.p, sa.x(), Xb.p, sb.x(), m, points);
      if (tb == ShapeType::Box) count = collide_sphere_box(Xa.p, sa.x(), Xb, sb, m, points);
      if (tb == ShapeType::Capsule) count = collide_sphere_capsule(Xa.p, sa.x(), Xb, sb.x(), sb.y(), m, points);
      break;
    case ShapeType::Box:
      if (tb == ShapeType::Box) count = collide_box_box(Xa, sa, Xb, sb, m, points);
      if (tb == ShapeType::Capsule) {
        count = collide_capsule_box(Xb, sb.x(), sb.y(), Xa, sa, m, points);
        for (int k = 0; k < count; ++k) points[k].normal = -points[k].normal;
      }
      break;
    case ShapeType::Capsule: count = collide_capsule_capsule(Xa, sa.x(), sa.y(), Xb, sb.x(), sb.y(), m, points); break;
  }
  for (int k = 0; k < count; ++k) out.push_back({a, b, points[k]});
}

}  // namespace novaphy
