#include "engine/collision.h"

#include <omp.h>

#include <algorithm>
#include <numeric>

#include "engine/error.h"
#include "kernels/collide.h"

namespace novaphy {

namespace {

// the warm-start bookkeeping of a buffer of contact_capacity contacts
void size_previous(Contacts& c) {
  c.previous_key.resize(c.contact_capacity);
  c.previous_impulse.resize(3 * static_cast<size_t>(c.contact_capacity));
  c.previous_match.assign(c.contact_capacity, -1);
}

}  // namespace

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
  world_planes_.resize(model.world_count);
  for (int s = 0; s < model.shape_count; ++s) {
    // a shape with an empty group or mask never collides: the broad phase never sees it
    if (model.shape_collision_group[s] == 0 || model.shape_collision_mask[s] == 0) continue;
    const int w = model.shape_world[s];
    if (model.shape_type[s] == static_cast<int>(ShapeType::Plane)) {
      planes_.push_back(s);
      (w < 0 ? shared_planes_ : world_planes_[w]).push_back(s);
      continue;
    }
    others_.push_back(s);
    (w < 0 ? shared_others_ : world_others_[w]).push_back(s);
  }
  world_sweep_ = world_others_;
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
  size_previous(c);
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

  // this step's contacts, in their order, become the previous ones for warm starting (a buffer not
  // made by contacts() gets its bookkeeping here)
  if (contacts.previous_match.size() != static_cast<size_t>(contacts.contact_capacity)) size_previous(contacts);
  for (int c = 0; c < contacts.contact_count; ++c) {
    contacts.previous_key[c] = contacts.key_of(c);
    for (int i = 0; i < 3; ++i) contacts.previous_impulse[3 * c + i] = contacts.contact_impulse[3 * c + i];
  }
  contacts.previous_count = contacts.contact_count;
  contacts.contact_count = 0;
  contacts.contact_dropped = 0;

  // the bounds of the shapes of no world first: every world meets them. Then per world, while its
  // shapes' bounds are in cache: sweep and prune along x, then its planes and the shared ones against
  // its shapes. Then the shapes of no world against all others, and every plane against them. Worlds
  // (and shared shapes, and planes) spread over threads
  for (const int s : shared_others_) bounds(state, s);
  auto overlap = [&](int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (lower_[3 * b + k] > upper_[3 * a + k] || lower_[3 * a + k] > upper_[3 * b + k]) return false;
    return true;
  };
  auto test_pair = [&](int a, int b, std::vector<Found>& out) {
    if (overlap(a, b) && may_collide(a, b)) narrow_phase(std::min(a, b), std::max(a, b), state, out);
  };
  find_contacts(model_.world_count, contacts, [&](int w, std::vector<Found>& out) {
    for (const int s : world_others_[w]) bounds(state, s);
    std::vector<int>& order = world_sweep_[w];
    std::sort(order.begin(), order.end(),
              [&](int x, int y) { return lower_[3 * x] < lower_[3 * y] || (lower_[3 * x] == lower_[3 * y] && x < y); });
    for (size_t i = 0; i < order.size(); ++i)
      for (size_t j = i + 1; j < order.size() && lower_[3 * order[j]] <= upper_[3 * order[i]]; ++j)
        test_pair(order[i], order[j], out);
    // the world's planes and the shared ones, in index order
    const std::vector<int>& own = world_planes_[w];
    for (size_t i = 0, j = 0; i < own.size() || j < shared_planes_.size();) {
      const bool take_own = j == shared_planes_.size() || (i < own.size() && own[i] < shared_planes_[j]);
      against_plane(take_own ? own[i++] : shared_planes_[j++], world_others_[w], state, out);
    }
  });
  find_contacts(static_cast<int>(shared_others_.size()), contacts, [&](int i, std::vector<Found>& out) {
    for (const int b : others_)
      if (b != shared_others_[i] && (model_.shape_world[b] >= 0 || b > shared_others_[i]))
        test_pair(shared_others_[i], b, out);
  });
  find_contacts(static_cast<int>(planes_.size()), contacts,
                [&](int i, std::vector<Found>& out) { against_plane(planes_[i], shared_others_, state, out); });
  match_previous(contacts);
}

void CollisionPipeline::bounds(const State& state, int s) {
  shape_bounds(model_, shape_pose(model_, state, s), s, options_.margin, &lower_[3 * s], &upper_[3 * s]);
}

void CollisionPipeline::against_plane(int p, const std::vector<int>& shapes, const State& state,
                                      std::vector<Found>& out) const {
  const Transform X = shape_pose(model_, state, p);
  const Vec3 n = X.q * Vec3::UnitY();
  for (const int s : shapes) {
    const Vec3 lo = Eigen::Map<const Vec3>(&lower_[3 * s]), hi = Eigen::Map<const Vec3>(&upper_[3 * s]);
    const Scalar distance = n.dot(0.5 * (lo + hi) - X.p) - 0.5 * (hi - lo).cwiseAbs().dot(n.cwiseAbs());
    if (distance <= 0 && may_collide(p, s)) narrow_phase(p, s, state, out);
  }
}

void CollisionPipeline::match_previous(Contacts& contacts) {
  // a contact is most often found where it was, right after the contact matched before it; otherwise
  // among the previous contacts sorted by key (sorted once per collide, when first needed)
  const int n = contacts.previous_count;
  const std::vector<std::uint64_t>& key = contacts.previous_key;
  previous_order_.clear();
  int next = 0;
  for (int c = 0; c < contacts.contact_count; ++c) {
    const std::uint64_t k = contacts.key_of(c);
    int m = -1;
    if (next < n && key[next] == k) {
      m = next;
    } else if (n > 0) {
      if (previous_order_.empty()) {
        previous_order_.resize(n);
        std::iota(previous_order_.begin(), previous_order_.end(), 0);
        std::sort(previous_order_.begin(), previous_order_.end(),
                  [&](int x, int y) { return key[x] < key[y] || (key[x] == key[y] && x < y); });
      }
      const auto it = std::lower_bound(previous_order_.begin(), previous_order_.end(), k,
                                       [&](int x, std::uint64_t value) { return key[x] < value; });
      if (it != previous_order_.end() && key[*it] == k) m = *it;
    }
    contacts.previous_match[c] = m;
    if (m >= 0) next = m + 1;
  }
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
