// The broad phase of CollisionPipeline (engine/collision/pipeline.h): shapes' bounds, and worlds alike stepped a
// group at a time in lanes (a world per lane): their grouping when the pipeline is made, their boxes, their
// pairs' overlaps and their planes' reach at each collide.
#include <algorithm>
#include <numeric>

#include "engine/collision/pipeline.h"
#include "kernels/collide.h"
#include "kernels/lane_transpose.h"

namespace novaphy {

void CollisionPipeline::group_worlds() {
  // consecutive worlds alike, up to kLanes<Scalar> of them, have their boxes, their pairs' overlaps and
  // their planes' reach found together, a world per lane
  const int world_count = model_.world_count;
  for (int w = 0; w < world_count;) {
    int end = w + 1;
    while (end < world_count && end - w < kLanes<Scalar> && alike(w, end)) ++end;
    group_first_.push_back(w);
    w = end;
  }
  group_first_.push_back(world_count);
}

void CollisionPipeline::describe_groups() {
  // per group of several: each shape's body in each lane (-1: none; the first world's again in lanes
  // past the group's), and a bit per shape whose local pose and size, and what the narrow phase reads of it, are
  // the same in all its worlds (read once: a replicated robot's), where group_boxes and the narrow phase read the
  // model's arrays from the first world only (a collide after a step finds little of them in cache); the runs of
  // bodies its lanes' shapes lie in (group_run_), and its planes (each the same in all its worlds, or not)
  const int groups = static_cast<int>(group_first_.size()) - 1;
  group_body_start_.assign(groups, -1);
  group_same_.assign(groups, 0);
  group_read_.assign(groups, -1);
  group_run_.assign(groups, {});
  group_plane_start_.assign(1, 0);
  group_slot_start_.assign(1, 0);
  int last_read = -1;
  std::vector<int> read_planes;
  for (int g = 0; g < groups; ++g) {
    const int first = group_first_[g], count = group_first_[g + 1] - first;
    if (count > 1) {
      group_shapes(g, last_read);
      last_read = group_read_[g];
      group_runs(g);
      group_plane_reach(g, read_planes);
      group_slots(g);
    }
    group_plane_start_.push_back(static_cast<int>(group_plane_read_.size()));
    group_slot_start_.push_back(static_cast<int>(group_slot_shapes_.size()));
  }
}

void CollisionPipeline::group_slots(int g) {
  constexpr int L = kLanes<Scalar>;
  const int first = group_first_[g], start = static_cast<int>(group_slot_shapes_.size());
  const int n = static_cast<int>(world_others_[first].size());
  const int* body = group_body_.data() + group_body_start_[g];
  std::vector<int> slot(n, -1);
  for (int i = 0; i < n; ++i) {
    for (int u = start; u < static_cast<int>(group_slot_shapes_.size()) && slot[i] < 0 && body[L * i] >= 0; ++u) {
      const int j = __builtin_ctzll(group_slot_shapes_[u]);
      if (std::equal(body + L * i, body + L * (i + 1), body + L * j)) slot[i] = u - start;
    }
    if (slot[i] < 0) {
      slot[i] = static_cast<int>(group_slot_shapes_.size()) - start;
      group_slot_shapes_.push_back(0);
    }
    group_slot_shapes_[start + slot[i]] |= std::uint64_t{1} << i;
  }
  group_slot_pairs_.resize(group_slot_shapes_.size(), 0);
  const std::uint64_t* mask = world_pairs_.data() + world_pair_start_[first];
  for (int i = 0; i < n; ++i)
    for (std::uint64_t m = mask[i]; m != 0; m &= m - 1)
      group_slot_pairs_[start + slot[i]] |= std::uint64_t{1} << slot[__builtin_ctzll(m)];
}

void CollisionPipeline::group_shapes(int g, int last_read) {
  const int L = kLanes<Scalar>;
  const int first = group_first_[g], count = group_first_[g + 1] - first;
  const std::vector<int>& shapes = world_others_[first];
  const int n = static_cast<int>(shapes.size());
  group_body_start_[g] = static_cast<int>(group_body_.size());
  for (int i = 0; i < n; ++i) {
    bool same = true;
    for (int l = 0; l < L; ++l) {
      const int s = world_others_[first + (l < count ? l : 0)][i];
      group_body_.push_back(model_.shape_body[s]);
      same &= read_alike(s, shapes[i]);
    }
    if (same) group_same_[g] |= std::uint64_t{1} << i;
  }
  group_read_[g] = first;
  if (last_read < 0 || static_cast<int>(world_others_[last_read].size()) != n) return;
  for (std::uint64_t m = group_same_[g]; m != 0; m &= m - 1)
    if (!read_alike(world_others_[last_read][__builtin_ctzll(m)], shapes[__builtin_ctzll(m)])) return;
  group_read_[g] = last_read;
}

void CollisionPipeline::group_plane_reach(int g, std::vector<int>& read_planes) {
  constexpr int L = kLanes<Scalar>;
  constexpr std::size_t kReadPlanes = 8;  // (a model of many different planes reads its own beyond these)
  const int first = group_first_[g], count = group_first_[g + 1] - first;
  const std::vector<int>& shapes = world_others_[first];
  const int n = static_cast<int>(shapes.size());
  const Scalar* transform = model_.shape_transform.data();
  auto fixed_at = [&](int p, int q) {  // p on no body, where q is
    return model_.shape_body[p] < 0 && std::equal(transform + 7 * p, transform + 7 * p + 7, transform + 7 * q);
  };
  for (const int code : plane_order(first)) {
    const int p0 = plane_of(first, code);
    std::uint64_t reach = 0;
    for (int i = 0; i < n; ++i)
      if (may_collide(p0, shapes[i])) reach |= std::uint64_t{1} << i;
    bool same = true, still = true;
    for (int l = 0; l < L; ++l) {
      const int p = plane_of(first + (l < count ? l : 0), code);
      group_plane_lanes_.push_back(p);
      same &= narrow_alike(p, p0);
      still &= fixed_at(p, p0);
    }
    int read = -1;
    if (same) {
      const auto alike = [&](int q) { return narrow_alike(q, p0) && (!still || fixed_at(q, p0)); };
      const auto before = std::find_if(read_planes.begin(), read_planes.end(), alike);
      read = before != read_planes.end() ? *before : p0;
      if (read == p0 && read_planes.size() < kReadPlanes) read_planes.push_back(p0);
    }
    group_plane_shapes_.push_back(reach);
    group_plane_read_.push_back(read);
    group_plane_still_.push_back(same && still);
  }
}

bool CollisionPipeline::read_alike(int s, int a) const {
  bool same = narrow_alike(s, a);
  for (int k = 0; k < 7; ++k) same &= model_.shape_transform[7 * s + k] == model_.shape_transform[7 * a + k];
  return same;
}

bool CollisionPipeline::narrow_alike(int s, int a) const {
  const Model& model = model_;
  bool same = model.shape_type[s] == model.shape_type[a] && model.shape_mesh[s] == model.shape_mesh[a] &&
              model.shape_margin[s] == model.shape_margin[a];
  for (int k = 0; k < 3; ++k) same &= model.shape_scale[3 * s + k] == model.shape_scale[3 * a + k];
  for (int k = 0; k < 2; ++k) same &= model.shape_solref[2 * s + k] == model.shape_solref[2 * a + k];
  return same;
}

bool CollisionPipeline::alike(int v, int w) const {
  // both test their pairs by masks, the same masks, over shapes of the same types, each on a body or not;
  // they meet planes in the same order, each the same shapes
  const std::vector<int>&a = world_others_[v], &b = world_others_[w];
  if (world_pair_start_[v] < 0 || world_pair_start_[w] < 0 || a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (model_.shape_type[a[i]] != model_.shape_type[b[i]] ||
        (model_.shape_body[a[i]] < 0) != (model_.shape_body[b[i]] < 0) ||
        world_pairs_[world_pair_start_[v] + i] != world_pairs_[world_pair_start_[w] + i])
      return false;
  const std::vector<int> order = plane_order(v);
  if (order != plane_order(w)) return false;
  for (const int code : order)
    for (size_t i = 0; i < a.size(); ++i)
      if (may_collide(plane_of(v, code), a[i]) != may_collide(plane_of(w, code), b[i])) return false;
  return true;
}

void CollisionPipeline::group_runs(int g) {
  // each lane's run starts at the lowest body its shapes sit on; a run serves when every lane's shapes
  // sit at the same places in it and it is at most twice as long as the shapes are many (otherwise, as
  // where a world's bodies lie among other worlds', its shapes' bodies are read number by number)
  constexpr int L = kLanes<Scalar>;
  const int n = static_cast<int>(world_others_[group_first_[g]].size());
  const int* body = group_body_.data() + group_body_start_[g];
  BodyRun run;
  std::vector<int> local(n, -1);
  for (int l = 0; l < L; ++l) {
    run.first[l] = -1;
    for (int i = 0; i < n; ++i)
      if (body[L * i + l] >= 0 && (run.first[l] < 0 || body[L * i + l] < run.first[l])) run.first[l] = body[L * i + l];
  }
  for (int i = 0; i < n; ++i) {
    if (body[L * i] < 0) continue;  // (alike: no lane has a body for it)
    local[i] = body[L * i] - run.first[0];
    for (int l = 1; l < L; ++l)
      if (body[L * i + l] - run.first[l] != local[i]) return;
    run.length = std::max(run.length, local[i] + 1);
  }
  if (run.length == 0 || run.length > 2 * n) return;
  group_run_[g] = run;
  group_local_.resize(static_cast<size_t>(group_body_start_[g] / L + n), -1);
  std::copy(local.begin(), local.end(), group_local_.begin() + group_body_start_[g] / L);
}

namespace {

constexpr Scalar kIdentity[7] = {0, 0, 0, 0, 0, 0, 1};  // where a shape on no body has its "body"

BoundsKind bounds_kind(int type) {
  switch (static_cast<ShapeType>(type)) {
    case ShapeType::Sphere: return BoundsKind::Sphere;
    case ShapeType::Box: return BoundsKind::Box;
    case ShapeType::Capsule: return BoundsKind::Capsule;
    // (a cylinder, an ellipsoid and a mesh's hull lie within the box of their scale)
    case ShapeType::Cylinder:
    case ShapeType::Ellipsoid:
    case ShapeType::Mesh: return BoundsKind::Box;
    case ShapeType::Plane: break;
  }
  return BoundsKind::Plane;
}

}  // namespace

CollisionPipeline::Box CollisionPipeline::box(const State& state, int s) const {
  const int b = model_.shape_body[s];
  Scalar pose[7];
  Vec3 lower, upper;
  shape_bounds(bounds_kind(model_.shape_type[s]), b < 0 ? kIdentity : &state.body_q[7 * b],
               &model_.shape_transform[7 * s], &model_.shape_scale[3 * s], reach_, pose, lower.data(), upper.data());
  return {Transform::from_array(pose), lower, upper};
}

void CollisionPipeline::group_boxes(const State& state, int g, Scratch& scratch) const {
  using V = Lanes<Scalar>;
  constexpr int L = kLanes<Scalar>;
  const int first = group_first_[g], count = group_first_[g + 1] - first;
  const int n = static_cast<int>(world_others_[first].size());
  const int* group_body = group_body_.data() + group_body_start_[g];
  scratch.lanes.resize(n);
  // the lanes' runs of bodies moved into lanes at once (a tiled transpose), where the group has them
  const BodyRun& run = group_run_[g];
  const int* place = run.length > 0 ? &group_local_[group_body_start_[g] / L] : nullptr;
  if (run.length > 0) {
    const Scalar* rows[L];
    for (int l = 0; l < L; ++l) rows[l] = &state.body_q[7 * run.first[l]];
    scratch.body_q.resize(7 * run.length);
    lanes_from_rows<Scalar>(rows, 7 * run.length, scratch.body_q.data());
  }
  const std::vector<int>& read = world_others_[group_read_[g]];
  for (int i = 0; i < n; ++i) {
    // shape i of each world
    V gathered[7], local[7], scale[3];
    const V* body = gathered;
    if (place && place[i] >= 0) {
      body = &scratch.body_q[7 * place[i]];
    } else {
      for (int l = 0; l < L; ++l) {
        const int b = group_body[L * i + l];
        const Scalar* x = b < 0 ? kIdentity : &state.body_q[7 * b];
        for (int k = 0; k < 7; ++k) gathered[k][l] = x[k];
      }
    }
    const bool same = group_same_[g] >> i & 1;
    if (same) {
      const int s = read[i];
      for (int k = 0; k < 7; ++k) local[k] = V{} + model_.shape_transform[7 * s + k];
      for (int k = 0; k < 3; ++k) scale[k] = V{} + model_.shape_scale[3 * s + k];
    } else {
      for (int l = 0; l < L; ++l) {
        const int s = world_others_[first + (l < count ? l : 0)][i];
        for (int k = 0; k < 7; ++k) local[k][l] = model_.shape_transform[7 * s + k];
        for (int k = 0; k < 3; ++k) scale[k][l] = model_.shape_scale[3 * s + k];
      }
    }
    ShapeLanes& X = scratch.lanes[i];
    shape_bounds(bounds_kind(model_.shape_type[same ? read[i] : world_others_[first][i]]), body, local, scale, reach_,
                 X.pose, X.lower, X.upper);
  }
  // the slots' boxes, each joining its shapes'
  const int slot_start = group_slot_start_[g], slots = group_slot_start_[g + 1] - slot_start;
  const std::uint64_t* slot_shapes = group_slot_shapes_.data() + slot_start;
  const std::uint64_t* slot_pairs = group_slot_pairs_.data() + slot_start;
  scratch.slots.resize(slots);
  for (int u = 0; u < slots; ++u) {
    ShapeLanes& U = scratch.slots[u];
    std::uint64_t m = slot_shapes[u];
    const ShapeLanes& X = scratch.lanes[__builtin_ctzll(m)];
    std::copy(X.lower, X.lower + 3, U.lower);
    std::copy(X.upper, X.upper + 3, U.upper);
    for (m &= m - 1; m != 0; m &= m - 1) {
      const ShapeLanes& Y = scratch.lanes[__builtin_ctzll(m)];
      for (int k = 0; k < 3; ++k) {
        U.lower[k] = Y.lower[k] < U.lower[k] ? Y.lower[k] : U.lower[k];
        U.upper[k] = Y.upper[k] > U.upper[k] ? Y.upper[k] : U.upper[k];
      }
    }
  }
  // the pairs the masks allow whose boxes overlap, tested in every world at once, where their slots' boxes
  // overlap in some world
  scratch.hits.assign(static_cast<size_t>(L) * n, 0);
  const std::uint64_t* mask = world_pairs_.data() + world_pair_start_[first];
  for (int u = 0; u < slots; ++u) {
    const ShapeLanes& U = scratch.slots[u];
    for (std::uint64_t pairs = slot_pairs[u]; pairs != 0; pairs &= pairs - 1) {
      const int v = __builtin_ctzll(pairs);
      const ShapeLanes& W = scratch.slots[v];
      if (!any_lane<Scalar>(boxes_overlap(U.lower, U.upper, W.lower, W.upper))) continue;
      for (std::uint64_t shapes = slot_shapes[u]; shapes != 0; shapes &= shapes - 1) {
        const int i = __builtin_ctzll(shapes);
        const ShapeLanes& A = scratch.lanes[i];
        for (std::uint64_t m = mask[i] & slot_shapes[v]; m != 0; m &= m - 1) {
          const int j = __builtin_ctzll(m);
          const ShapeLanes& B = scratch.lanes[j];
          const IntLanes<Scalar> hit = boxes_overlap(A.lower, A.upper, B.lower, B.upper);
          if (!any_lane<Scalar>(hit)) continue;
          for (int l = 0; l < count; ++l)
            if (hit[l]) scratch.hits[l * n + i] |= std::uint64_t{1} << j;
        }
      }
    }
  }
}

void CollisionPipeline::group_planes(int g, Scratch& scratch) const {
  using V = Lanes<Scalar>;
  constexpr int L = kLanes<Scalar>;
  const int first = group_first_[g], count = group_first_[g + 1] - first;
  const int start = group_plane_start_[g], planes = group_plane_start_[g + 1] - start;
  const std::vector<int>&first_shapes = world_others_[first], &read = world_others_[group_read_[g]];
  const int n = static_cast<int>(first_shapes.size());
  scratch.plane_hits.assign(static_cast<size_t>(L) * planes, 0);
  scratch.plane_spheres.resize(static_cast<size_t>(planes) * n);
  scratch.spheres = 0;
  for (int i = 0; i < n; ++i) {
    const int s = group_same_[g] >> i & 1 ? read[i] : first_shapes[i];
    if (model_.shape_type[s] == static_cast<int>(ShapeType::Sphere)) scratch.spheres |= std::uint64_t{1} << i;
  }
  for (int k = 0; k < planes; ++k) {
    V origin[3], normal[3];
    const int *plane = &group_plane_lanes_[(start + k) * L], read_p = group_plane_read_[start + k];
    if (group_plane_still_[start + k]) {
      for (int m = 0; m < 3; ++m)
        origin[m] = V{} + plane_pose_[read_p].p[m], normal[m] = V{} + plane_normal_[read_p][m];
    } else {
      for (int l = 0; l < L; ++l)
        for (int m = 0; m < 3; ++m)
          origin[m][l] = plane_pose_[plane[l]].p[m], normal[m][l] = plane_normal_[plane[l]][m];
    }
    for (std::uint64_t m = group_plane_shapes_[start + k]; m != 0; m &= m - 1) {
      const int i = __builtin_ctzll(m);
      const ShapeLanes& X = scratch.lanes[i];
      const IntLanes<Scalar> hit = plane_box_distance(origin, normal, X.lower, X.upper) <= 0;
      if (!any_lane<Scalar>(hit)) continue;
      for (int l = 0; l < count; ++l)
        if (hit[l]) scratch.plane_hits[l * planes + k] |= std::uint64_t{1} << i;
      if (!(scratch.spheres >> i & 1)) continue;
      // the sphere's contacts in lanes, its radius and the pair's margin read once where alike in every world
      V radius, margin;
      const bool same = (group_same_[g] >> i & 1) && read_p >= 0;
      for (int l = 0; l < L; ++l) {
        const int s = same ? read[i] : world_others_[first + (l < count ? l : 0)][i];
        radius[l] = l > 0 && same ? radius[0] : model_.shape_scale[3 * s];
        margin[l] = l > 0 && same ? margin[0] : pair_margin(same ? read_p : plane[l], s);
      }
      SphereOnPlane& c = scratch.plane_spheres[k * n + i];
      c.touching = plane_sphere_contact<V>(origin, normal, X.pose, radius, margin, c.point, &c.depth);
    }
  }
}

void CollisionPipeline::lane_boxes(int l, std::uint64_t needed, Scratch& scratch) const {
  const int n = static_cast<int>(scratch.lanes.size());
  if (static_cast<int>(scratch.boxes.size()) < n) scratch.boxes.resize(n);
  for (std::uint64_t m = needed; m != 0; m &= m - 1) {
    const int i = __builtin_ctzll(m);
    const ShapeLanes& X = scratch.lanes[i];
    Box& box = scratch.boxes[i];
    box.pose.p = Vec3(X.pose[0][l], X.pose[1][l], X.pose[2][l]);
    box.pose.q = Quat(X.pose[6][l], X.pose[3][l], X.pose[4][l], X.pose[5][l]);
    box.lower = Vec3(X.lower[0][l], X.lower[1][l], X.lower[2][l]);
    box.upper = Vec3(X.upper[0][l], X.upper[1][l], X.upper[2][l]);
  }
}

}  // namespace novaphy
