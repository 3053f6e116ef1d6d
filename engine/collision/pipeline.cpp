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

// options checked, contact_capacity 0 replaced by its default (8 per shape, at least 64)
CollisionOptions checked_options(const Model& model, CollisionOptions options) {
  if (options.contact_capacity < 0) fail("contact_capacity must be >= 0, got ", options.contact_capacity);
  if (!(options.margin >= 0) || !std::isfinite(options.margin))
    fail("margin must be finite and >= 0, got ", options.margin);
  if (options.num_threads < 0) fail("num_threads must be >= 0 (0: OpenMP's default), got ", options.num_threads);
  if (options.contact_capacity == 0) options.contact_capacity = std::max(64, 8 * model.shape_count);
  return options;
}

// the box in a shape's frame that holds it, for boxes_apart: the box of its scale, as the broad phase bounds it
// (bounds_kind), but a capsule's, whose scale leaves out its caps (along y)
Vec3 holding_box(ShapeType type, const Vec3& scale) {
  return type == ShapeType::Capsule ? Vec3(scale.x(), scale.y() + scale.x(), scale.x()) : scale;
}

}  // namespace

CollisionPipeline::CollisionPipeline(const Model& model, const CollisionOptions& options)
    : model_(model),
      options_(checked_options(model, options)),
      filter_(model, options_.self_collision),
      shapes_(model, filter_),
      groups_(model, filter_, shapes_) {
  reach_ = options_.margin;
  for (int s = 0; s < model.shape_count; ++s) reach_ = std::max(reach_, model.shape_margin[s]);
  place_static_planes();
  shared_boxes_.resize(shapes_.shared_others.size());
  world_sweep_.resize(model.world_count);
  for (int w = 0; w < model.world_count; ++w) {
    if (shapes_.world_pair_start[w] >= 0) continue;  // (it tests its masked pairs)
    world_sweep_[w].resize(shapes_.world_others[w].size());
    std::iota(world_sweep_[w].begin(), world_sweep_[w].end(), 0);
  }
}

void CollisionPipeline::place_static_planes() {
  // a plane on no body stays where the model put it; those on bodies move (place_shared)
  const Model& model = model_;
  plane_pose_.resize(model.shape_count);
  plane_normal_.resize(model.shape_count);
  for (const int p : shapes_.planes) {
    if (model.shape_body[p] >= 0) continue;
    plane_pose_[p] = Transform::from_array(&model.shape_transform[7 * p]);
    plane_normal_[p] = plane_pose_[p].q * Vec3::UnitY();
  }
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
  const int groups = groups_.count(), previous = contacts.contact_count;
  const int shared = static_cast<int>(shapes_.shared_others.size()), planes = static_cast<int>(shapes_.planes.size());
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
  const int previous = contacts.contact_count, groups = groups_.count();
  const int shared = static_cast<int>(shapes_.shared_others.size()), planes = static_cast<int>(shapes_.planes.size());
#pragma omp for schedule(static) nowait
  for (int g = 0; g < groups; ++g) group_contacts(state, g, scratch);
  scratch.loop_end[0] = scratch.found.size();
#pragma omp for schedule(static) nowait
  for (int i = 0; i < shared; ++i)
    for (int k = i + 1; k < shared; ++k)
      test_pair(shapes_.shared_others[i], shared_boxes_[i], shapes_.shared_others[k], shared_boxes_[k], scratch.found,
                shapes_.shared_others[i], shapes_.shared_others[k]);
  scratch.loop_end[1] = scratch.found.size();
#pragma omp for schedule(static) nowait
  for (int i = 0; i < planes; ++i)
    against_plane(shapes_.planes[i], shapes_.shared_others.data(), shared_boxes_.data(), shared, scratch.found);
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
  const std::uint8_t* reset =
      std::find(state.world_reset.begin(), state.world_reset.end(), 1) != state.world_reset.end()
          ? state.world_reset.data()
          : nullptr;
#pragma omp for schedule(static)
  for (int r = 0; r < stretches; ++r)
    match_previous(contacts, r * kMatchStretch, std::min(kept, (r + 1) * kMatchStretch), reset);
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
  for (const int p : shapes_.moving_planes) {
    plane_pose_[p] = box(state, p).pose;
    plane_normal_[p] = plane_pose_[p].q * Vec3::UnitY();
  }
  for (size_t i = 0; i < shapes_.shared_others.size(); ++i) shared_boxes_[i] = box(state, shapes_.shared_others[i]);
}

void CollisionPipeline::group_contacts(const State& state, int g, Scratch& scratch) {
  const int first = groups_.first[g], count = groups_.first[g + 1] - first;
  if (count == 1) {
    world_contacts(state, first, scratch, nullptr);
    return;
  }
  group_boxes(state, g, scratch);
  group_planes(g, scratch);
  const int start = groups_.plane_start[g], planes = groups_.plane_start[g + 1] - start;
  const int* plane_lanes = groups_.plane_lanes.data() + start * kLanes<Scalar>;
  // the narrow phase reads a shape alike in every world of the group from the group's read world (in cache)
  scratch.read_same = groups_.same[g];
  scratch.read_shapes = shapes_.world_others[groups_.read_world[g]].data();
  for (int l = 0; l < count; ++l) {
    const std::vector<int>& shapes = shapes_.world_others[first + l];
    const int n = static_cast<int>(shapes.size());
    const std::uint64_t* hits = scratch.hits.data() + l * n;
    // the boxes the lane's narrow phase reads: the shapes of its pairs and those reaching its planes (all of
    // them where shapes of no world meet every shape)
    std::uint64_t needed = shapes_.shared_others.empty() || n == 0 ? 0 : ~std::uint64_t{0} >> (64 - n);
    for (int i = 0; i < n; ++i)
      if (hits[i] != 0) needed |= hits[i] | std::uint64_t{1} << i;
    for (int k = 0; k < planes; ++k) needed |= scratch.plane_hits[l * planes + k] & ~scratch.spheres;
    lane_boxes(l, needed, scratch);
    world_contacts(state, first + l, scratch, hits);
    for (int k = 0; k < planes; ++k) {
      // (a plane's pose and normal, where fixed alike in all worlds, and its entries, where alike, from the plane
      // read for all)
      const int p = plane_lanes[k * kLanes<Scalar> + l], read = groups_.plane_read[start + k];
      const int read_p = read >= 0 ? read : p, placed = groups_.plane_still[start + k] ? read : p;
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
  const std::vector<int>& shapes = shapes_.world_others[w];
  const int n = static_cast<int>(shapes.size());
  auto read = [&](int i) { return hits ? scratch.read(i, shapes) : shapes[i]; };
  std::vector<Box>& boxes = scratch.boxes;
  if (!hits) {
    if (static_cast<int>(boxes.size()) < n) boxes.resize(n);
    for (int i = 0; i < n; ++i) boxes[i] = box(state, shapes[i]);
  }
  if (hits || shapes_.world_pair_start[w] >= 0) {
    const std::uint64_t* mask = hits ? hits : shapes_.world_pairs.data() + shapes_.world_pair_start[w];
    for (int i = 0; i < n; ++i)
      for (std::uint64_t m = mask[i]; m != 0; m &= m - 1) {
        const int j = __builtin_ctzll(m);
        if (hits || overlap(boxes[i], boxes[j]))
          narrow_phase(shapes[i], boxes[i].pose, shapes[j], boxes[j].pose, out, read(i), read(j));
      }
  } else {
    sweep_world(w, boxes, out);
  }
  for (size_t i = 0; i < shapes_.shared_others.size(); ++i)
    for (int j = 0; j < n; ++j)
      test_pair(shapes_.shared_others[i], shared_boxes_[i], shapes[j], boxes[j], out, shapes_.shared_others[i],
                read(j));
  if (hits) return;  // (its group's planes follow)
  // the world's planes and the shared ones, in index order
  const std::vector<int>& own = shapes_.world_planes[w];
  for (size_t i = 0, j = 0; i < own.size() || j < shapes_.shared_planes.size();) {
    const bool take_own = j == shapes_.shared_planes.size() || (i < own.size() && own[i] < shapes_.shared_planes[j]);
    against_plane(take_own ? own[i++] : shapes_.shared_planes[j++], shapes.data(), boxes.data(), n, out);
  }
}

void CollisionPipeline::against_plane(int p, const int* shapes, const Box* boxes, int count,
                                      std::vector<Found>& out) const {
  const Transform& X = plane_pose_[p];
  for (int i = 0; i < count; ++i) {
    const Box& b = boxes[i];
    const Scalar distance = plane_box_distance(X.p.data(), plane_normal_[p].data(), b.lower.data(), b.upper.data());
    if (distance <= 0 && filter_.may_collide(p, shapes[i])) narrow_phase(p, X, shapes[i], b.pose, out, p, shapes[i]);
  }
}

int CollisionPipeline::list_part(std::uint64_t key) const {
  const auto a = static_cast<std::int64_t>(key >> 40), b = static_cast<std::int64_t>((key >> 16) & 0xffffff);
  if (a >= model_.shape_count || b >= model_.shape_count) return std::numeric_limits<int>::max();
  const int part = std::max(shapes_.shape_part[a], shapes_.shape_part[b]);
  return part >= 0 ? part : std::numeric_limits<int>::max();
}

void CollisionPipeline::match_previous(Contacts& contacts, int begin, int end, const std::uint8_t* reset) const {
  // a contact is most often where the one before it matched, + 1 (the first of a stretch: at its own place);
  // otherwise among the previous contacts of its part of the list (list_part), which are listed together, the
  // parts ascending. A contact of a world reset matches none
  const int n = contacts.previous_count;
  const std::vector<std::uint64_t>& key = contacts.previous_key;
  int next = begin;
  for (int c = begin; c < end; ++c) {
    const std::uint64_t k = contacts.key_of(c);
    int m = -1;
    if (reset) {
      const int part = list_part(k);
      if (part != std::numeric_limits<int>::max() && reset[part]) {
        contacts.previous_match[c] = -1;
        ++next;
        continue;
      }
    }
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
