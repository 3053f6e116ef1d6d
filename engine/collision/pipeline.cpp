#include "engine/collision/pipeline.h"

#include <omp.h>

#include <algorithm>
#include <limits>
#include <numeric>

#include "engine/model/error.h"
#include "engine/threads/exclusive_call.h"
#include "engine/threads/parallel.h"
#include "kernels/collide.h"
#include "kernels/lane_transpose.h"

namespace novaphy {

namespace {

// the warm-start bookkeeping of a buffer of contact_capacity contacts
void size_previous(Contacts& c) {
  c.previous_key.resize(c.contact_capacity);
  c.previous_impulse.resize(6 * static_cast<size_t>(c.contact_capacity));
  c.previous_match.assign(c.contact_capacity, -1);
}

// the box in a shape's frame that holds it, for boxes_apart: the box of its scale, as the broad phase bounds it
// (bounds_kind), but a capsule's, whose scale leaves out its caps (along y)
Vec3 holding_box(ShapeType type, const Vec3& scale) {
  return type == ShapeType::Capsule ? Vec3(scale.x(), scale.y() + scale.x(), scale.x()) : scale;
}

}  // namespace

CollisionPipeline::CollisionPipeline(const Model& model, const CollisionOptions& options)
    : model_(model), options_(options) {
  if (options.contact_capacity < 0) fail("contact_capacity must be >= 0, got ", options.contact_capacity);
  if (!(options.margin >= 0) || !std::isfinite(options.margin))
    fail("margin must be finite and >= 0, got ", options.margin);
  if (options.num_threads < 0) fail("num_threads must be >= 0 (0: OpenMP's default), got ", options.num_threads);
  if (options_.contact_capacity == 0) options_.contact_capacity = std::max(64, 8 * model.shape_count);
  reach_ = options_.margin;
  for (int s = 0; s < model.shape_count; ++s) reach_ = std::max(reach_, model.shape_margin[s]);
  list_exclusions();
  link_bodies();
  sort_shapes();
  mask_pairs();
  group_worlds();
  describe_groups();
  place_static_planes();
  shared_boxes_.resize(shared_others_.size());
}

void CollisionPipeline::link_bodies() {
  const Model& model = model_;
  body_parent_.assign(model.body_count, -1);
  body_articulation_.assign(model.body_count, -1);
  for (int j = 0; j < model.joint_count; ++j) {
    // the parent through massless links (a MuJoCo body with several joints is a chain of them)
    int parent = model.joint_parent[j];
    while (parent >= 0 && model.body_mass[parent] == 0) parent = body_parent_[parent];
    body_parent_[model.joint_child[j]] = parent;
    body_articulation_[model.joint_child[j]] = model.joint_articulation[j];
  }
}

bool CollisionPipeline::visual_only(int s) const {
  const int group = model_.shape_collision_group[s], mask = model_.shape_collision_mask[s];
  return model_.collision_filter == CollisionFilter::Mujoco ? group == 0 && mask == 0 : group == 0 || mask == 0;
}

void CollisionPipeline::list_exclusions() {
  // per shape, the shapes it is excluded with, ascending
  const Model& model = model_;
  exclude_start_.assign(model.shape_count + 1, 0);
  for (int e = 0; e < model.exclude_count; ++e)
    for (int k = 0; k < 2; ++k) {
      const int s = model.exclude_shape[2 * e + k];
      if (s < 0 || s >= model.shape_count)
        fail("exclude_shape[", e, "] names shape ", s, ", the model has ", model.shape_count);
      ++exclude_start_[s + 1];
    }
  for (int s = 0; s < model.shape_count; ++s) exclude_start_[s + 1] += exclude_start_[s];
  exclude_other_.resize(exclude_start_.back());
  std::vector<int> next(exclude_start_.begin(), exclude_start_.end() - 1);
  for (int e = 0; e < model.exclude_count; ++e) {
    const int a = model.exclude_shape[2 * e], b = model.exclude_shape[2 * e + 1];
    exclude_other_[next[a]++] = b;
    exclude_other_[next[b]++] = a;
  }
  for (int s = 0; s < model.shape_count; ++s)
    std::sort(exclude_other_.begin() + exclude_start_[s], exclude_other_.begin() + exclude_start_[s + 1]);
}

bool CollisionPipeline::excluded(int a, int b) const {
  const auto begin = exclude_other_.begin() + exclude_start_[a], end = exclude_other_.begin() + exclude_start_[a + 1];
  return begin != end && std::binary_search(begin, end, b);
}

void CollisionPipeline::sort_shapes() {
  const Model& model = model_;
  world_others_.resize(model.world_count);
  world_planes_.resize(model.world_count);
  shape_part_.assign(model.shape_count, -1);
  for (int s = 0; s < model.shape_count; ++s) {
    if (visual_only(s)) continue;  // the broad phase never sees it
    const int w = model.shape_world[s];
    if (model.shape_type[s] == static_cast<int>(ShapeType::Plane)) {
      planes_.push_back(s);
      (w < 0 ? shared_planes_ : world_planes_[w]).push_back(s);
      continue;
    }
    (w < 0 ? shared_others_ : world_others_[w]).push_back(s);
    shape_part_[s] = w;
  }
}

void CollisionPipeline::mask_pairs() {
  const Model& model = model_;
  world_sweep_.resize(model.world_count);
  world_pair_start_.assign(model.world_count, -1);
  for (int w = 0; w < model.world_count; ++w) {
    const std::vector<int>& shapes = world_others_[w];
    if (shapes.size() > kMaskedWorldShapes) {
      world_sweep_[w].resize(shapes.size());
      std::iota(world_sweep_[w].begin(), world_sweep_[w].end(), 0);
      continue;
    }
    world_pair_start_[w] = static_cast<int>(world_pairs_.size());
    for (size_t i = 0; i < shapes.size(); ++i) {
      std::uint64_t mask = 0;
      for (size_t j = i + 1; j < shapes.size(); ++j)
        if (may_collide(shapes[i], shapes[j])) mask |= std::uint64_t{1} << j;
      world_pairs_.push_back(mask);
    }
  }
}

void CollisionPipeline::place_static_planes() {
  // a plane on no body stays where the model put it; those on bodies move
  const Model& model = model_;
  plane_pose_.resize(model.shape_count);
  plane_normal_.resize(model.shape_count);
  for (const int p : planes_) {
    if (model.shape_body[p] >= 0) {
      moving_planes_.push_back(p);
      continue;
    }
    plane_pose_[p] = Transform::from_array(&model.shape_transform[7 * p]);
    plane_normal_[p] = plane_pose_[p].q * Vec3::UnitY();
  }
}

std::vector<int> CollisionPipeline::plane_order(int w) const {
  const std::vector<int>& own = world_planes_[w];
  std::vector<int> order;
  for (size_t i = 0, j = 0; i < own.size() || j < shared_planes_.size();) {
    const bool take_own = j == shared_planes_.size() || (i < own.size() && own[i] < shared_planes_[j]);
    order.push_back(take_own ? static_cast<int>(i++) : -1 - static_cast<int>(j++));
  }
  return order;
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
  const bool ab = (model_.shape_collision_group[a] & model_.shape_collision_mask[b]) != 0;
  const bool ba_ = (model_.shape_collision_group[b] & model_.shape_collision_mask[a]) != 0;
  if (model_.collision_filter == CollisionFilter::Mujoco ? !(ab || ba_) : !(ab && ba_)) return false;
  if (excluded(a, b)) return false;
  if (ba < 0 || bb < 0) return true;
  if (body_parent_[ba] == bb || body_parent_[bb] == ba) return false;
  return options_.self_collision || body_articulation_[ba] != body_articulation_[bb];
}

void CollisionPipeline::collide(const State& state, Contacts& contacts) {
  const ExclusiveCall exclusive(busy_, "CollisionPipeline.collide");
  const std::int64_t start = options_.count_serial_time ? now_ns() : 0;
  model_.check(state);
  if (!same_layout(contacts, model_) || contacts.model_id != model_.model_id)
    fail("contacts buffer was not made by this pipeline (shape_count ", contacts.shape_count, ", capacity ",
         contacts.contact_capacity, "; expected ", model_.shape_count, ", ", options_.contact_capacity, ")");
  const auto capacity = static_cast<size_t>(contacts.contact_capacity);
#define NOVAPHY_CHECK_CONTACT_SIZE(T, name, count, width)                                                         \
  if (contacts.name.size() != capacity * (width))                                                                 \
    fail("contacts buffer: " #name " has ", contacts.name.size(), " entries, its capacity ", capacity, " needs ", \
         capacity*(width));
  NOVAPHY_CONTACT_FIELDS(NOVAPHY_CHECK_CONTACT_SIZE)
#undef NOVAPHY_CHECK_CONTACT_SIZE
  // (a buffer not made by contacts() gets its warm-start bookkeeping here)
  if (contacts.previous_match.size() != capacity) size_previous(contacts);

  // the poses of the planes on bodies and the boxes of the shapes of no world first: every world meets
  // them. Then per world, its shapes' boxes into the thread's scratch (in cache while used): its pairs
  // (those its masks allow whose bounds overlap, in index order; a world of many shapes sweeps and
  // prunes along x), the shapes of no world against its shapes, then its planes and the shared ones
  // against its shapes. Worlds alike go a group at a time: their boxes, their pairs' overlaps and their
  // planes' reach in lanes (group_boxes, group_planes), then each world's narrow phase in that order.
  // Then the shapes of no world against each other, and every plane against them. Groups of worlds (and
  // shared shapes, and planes) spread over threads, in one parallel region (find_on_thread)
  place_shared(state);
  const int groups = static_cast<int>(group_first_.size()) - 1, previous = contacts.contact_count;
  const int shared = static_cast<int>(shared_others_.size()), planes = static_cast<int>(planes_.size());
  const int threads = std::max({team(groups, kWorldsPerThread / kLanes<Scalar>), team(shared, kWorldsPerThread),
                                team(planes, kWorldsPerThread), team(previous, kKeptPerThread)});
  if (static_cast<int>(scratch_.size()) < threads) scratch_.resize(threads);
  int found = 0;
  {
    const ParallelTimer timer(timed(threads), &serial_seconds_.parallel);
    if (threads > 1 || omp_in_parallel()) {
#pragma omp parallel num_threads(threads)
      find_on_thread(state, contacts, &found);
    } else {
      find_on_thread(state, contacts, &found);
    }
  }
  if (found > contacts.contact_capacity && options_.on_overflow == ContactOverflow::Raise)
    fail("contact capacity ", contacts.contact_capacity, " is too small: collide found ", found,
         " contacts (make the pipeline with contact_capacity >= ", found,
         ", or on_overflow Grow); the buffer is left as it was");
  contacts.contact_count = std::min(found, contacts.contact_capacity);
  contacts.contact_dropped = found - contacts.contact_count;
  if (!options_.count_serial_time) return;
  serial_seconds_.step += 1e-9 * static_cast<double>(now_ns() - start);
  ++serial_seconds_.steps;
}

void Contacts::grow(int capacity) {
  contact_capacity = capacity;
#define NOVAPHY_GROW_CONTACT(T, name, count, width)                           \
  retired.push_back(std::make_shared<const std::vector<T>>(std::move(name))); \
  name.assign(static_cast<size_t>(capacity) * (width), T{});
  NOVAPHY_CONTACT_FIELDS(NOVAPHY_GROW_CONTACT)
#undef NOVAPHY_GROW_CONTACT
  previous_key.resize(capacity);
  previous_impulse.resize(6 * static_cast<size_t>(capacity));
  previous_match.assign(capacity, -1);
}

void CollisionPipeline::find_on_thread(const State& state, Contacts& contacts, int* found) {
  // the directives bind to the region collide opened, or to this thread alone: thread t runs the t-th run of each
  // loop's i (static schedules, without waiting between loops, which write only the thread's scratch)
  const int t = omp_get_thread_num(), n = omp_get_num_threads();
  Scratch& scratch = scratch_[t];
  scratch.found.clear();
  const int previous = contacts.contact_count, groups = static_cast<int>(group_first_.size()) - 1;
  const int shared = static_cast<int>(shared_others_.size()), planes = static_cast<int>(planes_.size());
#pragma omp for schedule(static) nowait
  for (int g = 0; g < groups; ++g) group_contacts(state, g, scratch);
  scratch.loop_end[0] = scratch.found.size();
#pragma omp for schedule(static) nowait
  for (int i = 0; i < shared; ++i)
    for (int k = i + 1; k < shared; ++k)
      test_pair(shared_others_[i], shared_boxes_[i], shared_others_[k], shared_boxes_[k], scratch.found,
                shared_others_[i], shared_others_[k]);
  scratch.loop_end[1] = scratch.found.size();
#pragma omp for schedule(static) nowait
  for (int i = 0; i < planes; ++i)
    against_plane(planes_[i], shared_others_.data(), shared_boxes_.data(), shared, scratch.found);
  scratch.loop_end[2] = scratch.found.size();
#pragma omp barrier
  std::size_t total = 0;
  for (int u = 0; u < n; ++u) total += scratch_[u].loop_end[2];
  if (t == 0) *found = static_cast<int>(total);
  const bool overflow = total > static_cast<std::size_t>(contacts.contact_capacity);
  if (overflow && options_.on_overflow == ContactOverflow::Raise) return;  // (every thread: collide throws)
    // the buffer's contacts, in their order, become the previous ones for warm starting
#pragma omp for schedule(static)
  for (int c = 0; c < previous; ++c) {
    contacts.previous_key[c] = contacts.key_of(c);
    for (int i = 0; i < 3; ++i) {
      contacts.previous_impulse[6 * c + i] = contacts.contact_impulse[3 * c + i];
      contacts.previous_impulse[6 * c + 3 + i] = contacts.contact_spin_impulse[3 * c + i];
    }
  }
  if (overflow && options_.on_overflow == ContactOverflow::Grow) {
#pragma omp single
    contacts.grow(
        static_cast<int>(std::max<std::size_t>(total, 2 * static_cast<std::size_t>(contacts.contact_capacity))));
  }
  if (t == 0) contacts.previous_count = previous;
  // each loop's contacts after the loops' before, each thread's after the threads' before: the order of the loops
  // and of i whatever the thread count; under Drop those beyond the capacity dropped
  std::size_t c = 0;
  for (int loop = 0; loop < 3; ++loop)
    for (int u = 0; u < n; ++u) {
      const std::size_t begin = loop > 0 ? scratch_[u].loop_end[loop - 1] : 0, end = scratch_[u].loop_end[loop];
      if (u == t)
        for (std::size_t k = begin; k < end && c + (k - begin) < static_cast<std::size_t>(contacts.contact_capacity);
             ++k)
          write_contact(scratch.found[k], static_cast<int>(c + (k - begin)), contacts);
      c += end - begin;
    }
  const int kept = static_cast<int>(std::min<std::size_t>(c, contacts.contact_capacity));
#pragma omp barrier
  // each contact matched with the previous ones, in stretches of a fixed length (what a stretch finds does not
  // depend on the threads)
  const int stretches = (kept + kMatchStretch - 1) / kMatchStretch;
#pragma omp for schedule(static)
  for (int r = 0; r < stretches; ++r)
    match_previous(contacts, r * kMatchStretch, std::min(kept, (r + 1) * kMatchStretch));
}

void CollisionPipeline::write_contact(const Found& found, int c, Contacts& contacts) const {
  contacts.contact_shape_a[c] = found.a;
  contacts.contact_shape_b[c] = found.b;
  contacts.contact_body_a[c] = model_.shape_body[found.a];
  contacts.contact_body_b[c] = model_.shape_body[found.b];
  Eigen::Map<Vec3>(&contacts.contact_point[3 * c]) = found.point.point;
  Eigen::Map<Vec3>(&contacts.contact_normal[3 * c]) = found.point.normal;
  contacts.contact_depth[c] = found.point.depth;
  contacts.contact_feature[c] = found.point.feature;
  Eigen::Map<Vec3>(&contacts.contact_impulse[3 * c]).setZero();
  Eigen::Map<Vec3>(&contacts.contact_spin_impulse[3 * c]).setZero();
}

void CollisionPipeline::place_shared(const State& state) {
  for (const int p : moving_planes_) {
    plane_pose_[p] = box(state, p).pose;
    plane_normal_[p] = plane_pose_[p].q * Vec3::UnitY();
  }
  for (size_t i = 0; i < shared_others_.size(); ++i) shared_boxes_[i] = box(state, shared_others_[i]);
}

void CollisionPipeline::group_contacts(const State& state, int g, Scratch& scratch) {
  const int first = group_first_[g], count = group_first_[g + 1] - first;
  if (count == 1) {
    world_contacts(state, first, scratch, nullptr);
    return;
  }
  group_boxes(state, g, scratch);
  group_planes(g, scratch);
  const int start = group_plane_start_[g], planes = group_plane_start_[g + 1] - start;
  const int* plane_lanes = group_plane_lanes_.data() + start * kLanes<Scalar>;
  // the narrow phase reads a shape alike in every world of the group from the group's read world (in cache)
  scratch.read_same = group_same_[g];
  scratch.read_shapes = world_others_[group_read_[g]].data();
  for (int l = 0; l < count; ++l) {
    const std::vector<int>& shapes = world_others_[first + l];
    const int n = static_cast<int>(shapes.size());
    const std::uint64_t* hits = scratch.hits.data() + l * n;
    // the boxes the lane's narrow phase reads: the shapes of its pairs and those reaching its planes (all of
    // them where shapes of no world meet every shape)
    std::uint64_t needed = shared_others_.empty() || n == 0 ? 0 : ~std::uint64_t{0} >> (64 - n);
    for (int i = 0; i < n; ++i)
      if (hits[i] != 0) needed |= hits[i] | std::uint64_t{1} << i;
    for (int k = 0; k < planes; ++k) needed |= scratch.plane_hits[l * planes + k] & ~scratch.spheres;
    lane_boxes(l, needed, scratch);
    world_contacts(state, first + l, scratch, hits);
    for (int k = 0; k < planes; ++k) {
      // (a plane's pose and normal, where fixed alike in all worlds, and its entries, where alike, from the plane
      // read for all)
      const int p = plane_lanes[k * kLanes<Scalar> + l], read = group_plane_read_[start + k];
      const int read_p = read >= 0 ? read : p, placed = group_plane_still_[start + k] ? read : p;
      for (std::uint64_t m = scratch.plane_hits[l * planes + k]; m != 0; m &= m - 1) {
        const int i = __builtin_ctzll(m);
        if (scratch.spheres >> i & 1) {  // (found in lanes by group_planes)
          const SphereOnPlane& c = scratch.plane_spheres[k * n + i];
          if (c.touching[l])
            scratch.found.push_back(
                {p,
                 shapes[i],
                 {Vec3(c.point[0][l], c.point[1][l], c.point[2][l]), plane_normal_[placed], c.depth[l], 0}});
          continue;
        }
        narrow_phase(p, plane_pose_[placed], shapes[i], scratch.boxes[i].pose, scratch.found, read_p,
                     scratch.read(i, shapes));
      }
    }
  }
}

void CollisionPipeline::world_contacts(const State& state, int w, Scratch& scratch, const std::uint64_t* hits) {
  std::vector<Found>& out = scratch.found;
  const std::vector<int>& shapes = world_others_[w];
  const int n = static_cast<int>(shapes.size());
  auto read = [&](int i) { return hits ? scratch.read(i, shapes) : shapes[i]; };
  std::vector<Box>& boxes = scratch.boxes;
  if (!hits) {
    if (static_cast<int>(boxes.size()) < n) boxes.resize(n);
    for (int i = 0; i < n; ++i) boxes[i] = box(state, shapes[i]);
  }
  if (hits || world_pair_start_[w] >= 0) {
    const std::uint64_t* mask = hits ? hits : world_pairs_.data() + world_pair_start_[w];
    for (int i = 0; i < n; ++i)
      for (std::uint64_t m = mask[i]; m != 0; m &= m - 1) {
        const int j = __builtin_ctzll(m);
        if (hits || overlap(boxes[i], boxes[j]))
          narrow_phase(shapes[i], boxes[i].pose, shapes[j], boxes[j].pose, out, read(i), read(j));
      }
  } else {
    sweep_world(w, boxes, out);
  }
  for (size_t i = 0; i < shared_others_.size(); ++i)
    for (int j = 0; j < n; ++j)
      test_pair(shared_others_[i], shared_boxes_[i], shapes[j], boxes[j], out, shared_others_[i], read(j));
  if (hits) return;  // (its group's planes follow)
  // the world's planes and the shared ones, in index order
  const std::vector<int>& own = world_planes_[w];
  for (size_t i = 0, j = 0; i < own.size() || j < shared_planes_.size();) {
    const bool take_own = j == shared_planes_.size() || (i < own.size() && own[i] < shared_planes_[j]);
    against_plane(take_own ? own[i++] : shared_planes_[j++], shapes.data(), boxes.data(), n, out);
  }
}

void CollisionPipeline::sweep_world(int w, const std::vector<Box>& boxes, std::vector<Found>& out) {
  const std::vector<int>& shapes = world_others_[w];
  const int n = static_cast<int>(shapes.size());
  std::vector<int>& order = world_sweep_[w];  // local indices
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    return boxes[x].lower.x() < boxes[y].lower.x() || (boxes[x].lower.x() == boxes[y].lower.x() && x < y);
  });
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n && boxes[order[j]].lower.x() <= boxes[order[i]].upper.x(); ++j)
      test_pair(shapes[order[i]], boxes[order[i]], shapes[order[j]], boxes[order[j]], out, shapes[order[i]],
                shapes[order[j]]);
}

void CollisionPipeline::against_plane(int p, const int* shapes, const Box* boxes, int count,
                                      std::vector<Found>& out) const {
  const Transform& X = plane_pose_[p];
  for (int i = 0; i < count; ++i) {
    const Box& b = boxes[i];
    const Scalar distance = plane_box_distance(X.p.data(), plane_normal_[p].data(), b.lower.data(), b.upper.data());
    if (distance <= 0 && may_collide(p, shapes[i])) narrow_phase(p, X, shapes[i], b.pose, out, p, shapes[i]);
  }
}

int CollisionPipeline::list_part(std::uint64_t key) const {
  const auto a = static_cast<std::int64_t>(key >> 40), b = static_cast<std::int64_t>((key >> 16) & 0xffffff);
  if (a >= model_.shape_count || b >= model_.shape_count) return std::numeric_limits<int>::max();
  const int part = std::max(shape_part_[a], shape_part_[b]);
  return part >= 0 ? part : std::numeric_limits<int>::max();
}

void CollisionPipeline::match_previous(Contacts& contacts, int begin, int end) const {
  // a contact is most often where the one before it matched, + 1 (the first of a stretch: at its own place);
  // otherwise among the previous contacts of its part of the list (list_part), which are listed together, the
  // parts ascending
  const int n = contacts.previous_count;
  const std::vector<std::uint64_t>& key = contacts.previous_key;
  int next = begin;
  for (int c = begin; c < end; ++c) {
    const std::uint64_t k = contacts.key_of(c);
    int m = -1;
    if (next < n && key[next] == k) {
      m = next;
    } else {
      const int part = list_part(k);
      int p = 0;
      for (int count = n; count > 0;) {  // the first previous contact of a part not before this one's
        const int half = count / 2;
        if (list_part(key[p + half]) < part) {
          p += half + 1;
          count -= half + 1;
        } else {
          count = half;
        }
      }
      for (; p < n && list_part(key[p]) == part; ++p)
        if (key[p] == k) {
          m = p;
          break;
        }
    }
    contacts.previous_match[c] = m;
    next = m >= 0 ? m + 1 : next + 1;
  }
}

int CollisionPipeline::thread_count() const {
  return team_choice().threads(options_.num_threads > 0 ? options_.num_threads : omp_get_max_threads());
}

int CollisionPipeline::team(int count, int grain) const {
  // no thread wakes for less than `grain` items: a small scene stays on one
  return std::max(1, std::min(thread_count(), count / grain));
}

bool CollisionPipeline::timed(int threads) const {
  return options_.count_serial_time && (threads > 1 || thread_count() == 1);
}

const HullView& CollisionPipeline::hull_view(int s, HullView* view) const {
  const int mesh = model_.shape_mesh[s];
  const int face0 = model_.mesh_face_start[mesh];
  view->vertex = &model_.mesh_vertex[3 * static_cast<size_t>(model_.mesh_vertex_start[mesh])];
  view->vertex_count = model_.mesh_vertex_start[mesh + 1] - model_.mesh_vertex_start[mesh];
  view->face_plane = &model_.mesh_face_plane[4 * static_cast<size_t>(face0)];
  view->corner_start = &model_.mesh_corner_start[face0];
  view->corner = model_.mesh_corner.data();
  view->face_count = model_.mesh_face_start[mesh + 1] - face0;
  return *view;
}

ConvexShape CollisionPipeline::convex_shape(int s, const Transform& pose, HullView* hull) const {
  static constexpr ConvexKind kKind[] = {ConvexKind::Sphere,  ConvexKind::Sphere,   ConvexKind::Box,
                                         ConvexKind::Capsule, ConvexKind::Cylinder, ConvexKind::Ellipsoid,
                                         ConvexKind::Hull};
  const auto type = static_cast<ShapeType>(model_.shape_type[s]);
  ConvexShape shape{kKind[static_cast<int>(type)], pose, Eigen::Map<const Vec3>(&model_.shape_scale[3 * s]), nullptr};
  if (type == ShapeType::Mesh) shape.hull = &hull_view(s, hull);
  return shape;
}

Scalar CollisionPipeline::pair_margin(int a, int b) const {
  const bool soft = model_.shape_solref[2 * a] != 0 && model_.shape_solref[2 * b] != 0;
  return soft ? std::max(model_.shape_margin[a], model_.shape_margin[b]) : options_.margin;
}

void CollisionPipeline::narrow_phase(int a, const Transform& pose_a, int b, const Transform& pose_b,
                                     std::vector<Found>& out, int read_a, int read_b) const {
  const bool swap = model_.shape_type[read_a] > model_.shape_type[read_b];
  if (swap) {
    std::swap(a, b);
    std::swap(read_a, read_b);
  }
  const auto ta = static_cast<ShapeType>(model_.shape_type[read_a]);
  const auto tb = static_cast<ShapeType>(model_.shape_type[read_b]);
  const Transform &Xa = swap ? pose_b : pose_a, &Xb = swap ? pose_a : pose_b;
  const Vec3 sa = Eigen::Map<const Vec3>(&model_.shape_scale[3 * read_a]);
  const Vec3 sb = Eigen::Map<const Vec3>(&model_.shape_scale[3 * read_b]);
  const Scalar m = pair_margin(read_a, read_b);
  // the pairs whose kernels search (capsule-box) or run MPR (cylinders, ellipsoids, meshes) first meet the boxes
  // that hold their shapes: most such pairs the broad phase lets through are apart (a tumbling Go1's trunk and
  // thighs, a swinging arm's links)
  const bool searched =
      (ta == ShapeType::Box && tb == ShapeType::Capsule) || (ta != ShapeType::Plane && tb >= ShapeType::Cylinder);
  if (searched && boxes_apart(Xa, holding_box(ta, sa), Xb, holding_box(tb, sb), m)) return;
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
    case ShapeType::Capsule:
      if (tb == ShapeType::Capsule) count = collide_capsule_capsule(Xa, sa.x(), sa.y(), Xb, sb.x(), sb.y(), m, points);
      break;
    default: break;
  }
  if (tb >= ShapeType::Cylinder) {
    HullView hull_a, hull_b;
    if (ta == ShapeType::Plane && tb == ShapeType::Cylinder)
      count = collide_plane_cylinder(Xa, Xb, sb.x(), sb.y(), m, points);
    else if (ta == ShapeType::Plane && tb == ShapeType::Ellipsoid)
      count = collide_plane_ellipsoid(Xa, Xb, sb, m, points);
    else if (ta == ShapeType::Plane)
      count = collide_plane_hull(Xa, Xb, hull_view(read_b, &hull_b), m, points);
    else
      count = collide_convex(convex_shape(read_a, Xa, &hull_a), convex_shape(read_b, Xb, &hull_b), m, points);
  }
  for (int k = 0; k < count; ++k) out.push_back({a, b, points[k]});
}

}  // namespace novaphy
